#!/bin/bash
# The container's entrypoint (docker/Dockerfile; docs/CONTAINER.md): starts gatekeeperd as PID 1
# on the data volume, in one of two modes chosen by what is mounted at /etc/gatekeeper:
#
#   nothing (default)        --listen 127.0.0.1:50051, gRPC local credentials: reachable from
#                            inside the container only (or the host's loopback with --network host)
#   server.pem + server.key  --listen 0.0.0.0:50051 with TLS; client-ca.pem (mutual TLS) and/or
#                            tokens (bearer tokens) must be there too: TLS alone would let anybody
#                            call, and gatekeeperd refuses that
#
# tokens alone (no TLS) keeps loopback and adds bearer tokens. gatekeeperd itself checks that
# server.key and tokens are private (chmod 600, owned by uid 10001) and that the certificate has
# not expired; this script only picks the flags and says which mode it chose.
#
# Arguments: flags are passed on to gatekeeperd; a flag given there replaces the default chosen
# here (e.g. --listen 127.0.0.1:6000, --log-level debug). With --config FILE.toml the file decides
# listen, data_dir and TLS, and no default is added but --port-file. An argument that is not a flag
# is run as a command instead (docker run ... gatekeeperd gatekeeper-cli --help).
#
# The paths can be moved for tests outside a container: GATEKEEPER_CONFIG_DIR (/etc/gatekeeper),
# GATEKEEPER_DATA_DIR (/data), GATEKEEPER_PORT (50051), GATEKEEPER_PORT_FILE
# (/tmp/gatekeeperd.port, read by the health check), GATEKEEPER_METRICS_PORT (9464: GET /metrics
# on the container's loopback, for a scraper sharing its network namespace; 0: any free port;
# "off": none), GATEKEEPER_METRICS_PORT_FILE (/tmp/gatekeeperd.metrics-port) and GATEKEEPERD
# (gatekeeperd).
set -euo pipefail

conf="${GATEKEEPER_CONFIG_DIR:-/etc/gatekeeper}"
data="${GATEKEEPER_DATA_DIR:-/data}"
port="${GATEKEEPER_PORT:-50051}"
port_file="${GATEKEEPER_PORT_FILE:-/tmp/gatekeeperd.port}"
metrics_port="${GATEKEEPER_METRICS_PORT:-9464}"
metrics_port_file="${GATEKEEPER_METRICS_PORT_FILE:-/tmp/gatekeeperd.metrics-port}"
daemon="${GATEKEEPERD:-gatekeeperd}"

if [ $# -gt 0 ] && [ "${1#-}" = "$1" ]; then
  exec "$@"
fi

say() { echo "gatekeeper-entrypoint: $*" >&2; }
given() {
  local a
  for a in "${user_args[@]}"; do
    case "$a" in "$1" | "$1"=*) return 0 ;; esac
  done
  return 1
}
args=()
default() { given "$1" || args+=("$1" "$2"); }

user_args=("$@")
# The health check reads the port once gatekeeperd has bound it; never a stale one.
rm -f "$port_file"
default --port-file "$port_file"
if [ "$metrics_port" != "off" ] && ! given --config && ! given --metrics-listen; then
  rm -f "$metrics_port_file"
  default --metrics-listen "127.0.0.1:$metrics_port"
  default --metrics-port-file "$metrics_port_file"
fi

if given --config; then
  say "--config given: listen, data_dir and TLS come from it (and from the flags given)"
elif [ -e "$conf/server.pem" ] || [ -e "$conf/server.key" ]; then
  for f in server.pem server.key; do
    if [ ! -r "$conf/$f" ]; then
      say "TLS: $conf/$f is missing or unreadable by uid $(id -u) (docs/CONTAINER.md)"
      exit 2
    fi
  done
  if [ ! -e "$conf/client-ca.pem" ] && [ ! -e "$conf/tokens" ]; then
    say "TLS beyond loopback needs client certificates ($conf/client-ca.pem) or bearer tokens ($conf/tokens), or both"
    exit 2
  fi
  default --listen "0.0.0.0:$port"
  default --tls-cert "$conf/server.pem"
  default --tls-key "$conf/server.key"
  [ ! -e "$conf/client-ca.pem" ] || default --tls-client-ca "$conf/client-ca.pem"
  [ ! -e "$conf/tokens" ] || default --token-file "$conf/tokens"
  default --data-dir "$data"
  say "TLS on port $port of every address$([ -e "$conf/client-ca.pem" ] && echo ", client certificates required")$([ -e "$conf/tokens" ] && echo ", bearer tokens required")"
else
  default --listen "127.0.0.1:$port"
  [ ! -e "$conf/tokens" ] || default --token-file "$conf/tokens"
  default --data-dir "$data"
  say "no TLS material in $conf: loopback only, gRPC local credentials (docs/CONTAINER.md)"
fi

exec "$daemon" "${args[@]}" "$@"
