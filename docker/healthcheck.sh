#!/bin/bash
# The container's HEALTHCHECK (docker/Dockerfile; docs/CONTAINER.md). Exit 0: healthy, 1: not.
#
# Debian 12 packages no gRPC health probe, so the check is gatekeeper-cli server-info (GetServerInfo,
# which any known token may call) on the port gatekeeperd wrote to its --port-file once serving,
# over the same transport the entrypoint chose from /etc/gatekeeper:
#
#   no server.pem    gRPC local credentials to 127.0.0.1:PORT
#   server.pem       TLS to 127.0.0.1:PORT when health-ca.pem (the CA that signed server.pem) is
#                    there, with health-client.pem/health-client.key as client certificate when
#                    client-ca.pem is there (mutual TLS), and GATEKEEPER_TLS_SERVER_NAME as the name
#                    to verify when server.pem is not issued for 127.0.0.1. Without health-ca.pem
#                    the check is only that PORT is listening (/proc/net/tcp{,6}): no credentials,
#                    no call.
#
# With a tokens file the call carries one of its tokens (a read one when there is one), handed to
# gatekeeper-cli on its standard input: never in the process list, never written elsewhere.
#
# The call goes to 127.0.0.1, which a --listen on 0.0.0.0 or 127.0.0.1 reaches; GATEKEEPER_HEALTH_HOST
# names another (e.g. ::1 as [::1]). Paths as in docker/entrypoint.sh: GATEKEEPER_CONFIG_DIR,
# GATEKEEPER_PORT_FILE; GATEKEEPER_CLI (gatekeeper-cli).
set -uo pipefail

conf="${GATEKEEPER_CONFIG_DIR:-/etc/gatekeeper}"
port_file="${GATEKEEPER_PORT_FILE:-/tmp/gatekeeperd.port}"
cli="${GATEKEEPER_CLI:-gatekeeper-cli}"

fail() {
  echo "unhealthy: $*"
  exit 1
}

port="$(cat "$port_file" 2> /dev/null)" || fail "gatekeeperd is not serving yet (no $port_file)"
if ! [[ "$port" =~ ^[0-9]+$ ]] || [ "$port" -eq 0 ] || [ "$port" -gt 65535 ]; then
  fail "$port_file holds no port"
fi

listening() {
  local hex table
  hex="$(printf '%04X' "$1")"
  for table in /proc/net/tcp /proc/net/tcp6; do
    [ -r "$table" ] || continue
    # "sl local_address rem_address st ...": local port in hex, state 0A is LISTEN
    while read -r _ local _ state _; do
      [ "${local##*:}" = "$hex" ] && [ "$state" = "0A" ] && return 0
    done < "$table"
  done
  return 1
}

flags=(--address "${GATEKEEPER_HEALTH_HOST:-127.0.0.1}:$port" --timeout 5)
if [ -e "$conf/server.pem" ]; then
  if [ ! -e "$conf/health-ca.pem" ]; then
    if listening "$port"; then
      echo "healthy: port $port is listening (TLS without $conf/health-ca.pem: no call made)"
      exit 0
    fi
    fail "nothing listens on port $port"
  fi
  flags+=(--tls-ca "$conf/health-ca.pem")
  if [ -e "$conf/client-ca.pem" ]; then
    if [ ! -r "$conf/health-client.pem" ] || [ ! -r "$conf/health-client.key" ]; then
      fail "mutual TLS: the health check needs $conf/health-client.pem and health-client.key (docs/CONTAINER.md)"
    fi
    flags+=(--tls-cert "$conf/health-client.pem" --tls-key "$conf/health-client.key")
  fi
  [ -z "${GATEKEEPER_TLS_SERVER_NAME:-}" ] || flags+=(--tls-server-name "$GATEKEEPER_TLS_SERVER_NAME")
fi

if [ -e "$conf/tokens" ]; then
  token="$(awk '$1 == "read" && NF == 2 { print $2; exit }' "$conf/tokens")"
  [ -n "$token" ] || token="$(awk '$1 ~ /^(write|admin)$/ && NF == 2 { print $2; exit }' "$conf/tokens")"
  [ -n "$token" ] || fail "no token in $conf/tokens"
  out="$(printf '%s\n' "$token" | "$cli" "${flags[@]}" --token-file /dev/stdin server-info 2>&1)" \
    || fail "$(printf '%s' "$out" | tr '\n' ' ' | cut -c1-300)"
else
  out="$("$cli" "${flags[@]}" server-info 2>&1 < /dev/null)" \
    || fail "$(printf '%s' "$out" | tr '\n' ' ' | cut -c1-300)"
fi
echo "healthy: gatekeeperd answers on port $port"
