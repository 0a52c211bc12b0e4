#!/usr/bin/env bash
# What CI can check of docker/Dockerfile without a Docker engine (docs/CONTAINER.md):
#   bash scripts/check_container.sh [BUILD_DIR]        (default: build)
#
#   1. the runtime stage: the last stage, FROM debian:12-slim, installing with apt-get
#      --no-install-recommends only packages that exist in Debian 12, none of them a compiler or
#      build tool, Chromium, Node/npm or a -dev package, and none of those among their Depends
#      either; no other installer (install_deps.sh, npm, pip, curl, ADD); from the build stage
#      only the two binaries
#   2. that list against the binaries: every library `ldd` resolves for BUILD_DIR's gatekeeperd and
#      gatekeeper-cli belongs (`dpkg -S`) to a listed package or to the base set below; and every
#      listed package owns at least one of them (the list is exact, not a guess)
#   3. a non-root USER, a HEALTHCHECK and an ENTRYPOINT naming files the stage copies in, /data
#      a volume
#   4. docker/entrypoint.sh and docker/healthcheck.sh: bash -n (and shellcheck when installed)
#   5. those two scripts run as they would in the container (uid 10001 when run as root) on
#      BUILD_DIR's binaries, with the configuration directory in each mode: loopback, loopback +
#      tokens, TLS + tokens (listening check and full check), mutual TLS, and TLS alone (refused)
#
# What it cannot check: that the image builds and starts (no Docker engine on this machine), nor
# files a library opens at run time other than through the dynamic linker.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${1:-build}"
DOCKERFILE=docker/Dockerfile
ENTRYPOINT_SH=docker/entrypoint.sh
HEALTHCHECK_SH=docker/healthcheck.sh
BINARIES=("$BUILD/server/gatekeeperd" "$BUILD/clients/gatekeeper-cli")

# What every debian:12-slim holds before the runtime stage installs anything: the C and C++
# runtimes and zlib, all four hard dependencies of apt (checked below against apt's Depends).
BASE_PACKAGES=(libc6 libgcc-s1 libstdc++6 zlib1g)

# Never in the runtime stage, nor among the Depends of what it installs.
FORBIDDEN='^(gcc|g\+\+|cpp|c\+\+|clang|clang-.*|llvm|llvm-[0-9]+|lld(-[0-9]+)?|lldb(-[0-9]+)?|gcc-[0-9]+|g\+\+-[0-9]+|cpp-[0-9]+|build-essential|cmake|cmake-data|ninja-build|make|ccache|binutils|binutils-.*|pkg-config|pkgconf|libtool|autoconf|automake|chromium|chromium-.*|nodejs|npm|libnode[0-9]*|node-.*|.*-dev)$'

failures=0
fail() {
  echo "FAIL: $*"
  failures=$((failures + 1))
}
ok() { echo "ok: $*"; }

[ -f "$DOCKERFILE" ] || { echo "FAIL: no $DOCKERFILE"; exit 1; }

# The Dockerfile as Docker reads it: comment lines dropped (also inside a continued instruction),
# continued lines joined; one instruction per line, prefixed by its stage number.
instructions() {
  awk '
    NR == 1 && /^#[ \t]*(syntax|escape|check)=/ { next }
    /^[ \t]*#/ { next }
    {
      line = $0
      sub(/\r$/, "", line)
      if (line ~ /\\[ \t]*$/) { sub(/\\[ \t]*$/, " ", line); acc = acc line; next }
      acc = acc line
      if (acc ~ /^[ \t]*$/) { acc = ""; next }
      sub(/^[ \t]+/, "", acc)
      if (toupper(acc) ~ /^FROM[ \t]/) stage++
      print stage "\t" acc
      acc = ""
    }' "$DOCKERFILE"
}
ALL="$(instructions)"
STAGES="$(printf '%s\n' "$ALL" | awk -F'\t' 'END { print $1 }')"
RUNTIME_FROM="$(printf '%s\n' "$ALL" | awk -F'\t' 'toupper($2) ~ /^FROM[ \t]/ && tolower($2) ~ /[ \t]as[ \t]+runtime[ \t]*$/ { print $1 "\t" $2 }')"

echo "== 1. the runtime stage of $DOCKERFILE"
if [ -z "$RUNTIME_FROM" ]; then
  echo "FAIL: no stage \"FROM ... AS runtime\" in $DOCKERFILE"
  exit 1
fi
RT_STAGE="${RUNTIME_FROM%%$'\t'*}"
RT="$(printf '%s\n' "$ALL" | awk -F'\t' -v s="$RT_STAGE" '$1 == s { sub(/^[^\t]*\t/, ""); print }')"
if [ "$RT_STAGE" = "$STAGES" ]; then
  ok "runtime is the last stage (the image docker build makes)"
else
  fail "the runtime stage is not the last one: docker build would make stage $STAGES"
fi
rt_base="$(printf '%s\n' "$RT" | awk 'NR == 1 { print tolower($2) }')"
case "$rt_base" in
  debian:12-slim | debian:bookworm-slim | debian:12-slim@* | debian:bookworm-slim@*) ok "FROM $rt_base" ;;
  *) fail "the runtime stage is FROM $rt_base: the base set (${BASE_PACKAGES[*]}) is only known for debian:12-slim" ;;
esac

# The packages each `apt-get install` / `apt install` of a RUN names (options, VAR=value, version
# pins and architectures dropped), and whether each such install refuses Recommends.
RUNTIME_PACKAGES=()
installs=0
while IFS= read -r run; do
  # one shell command per segment
  segments="$(printf '%s\n' "$run" | sed -E 's/(\&\&|\|\||;|\|)/\n/g')"
  while IFS= read -r seg; do
    read -r -a words <<< "$seg"
    i=0
    while [ $i -lt ${#words[@]} ] && [[ "${words[$i]}" == *=* || "${words[$i]}" == "RUN" ]]; do i=$((i + 1)); done
    [ $i -lt ${#words[@]} ] || continue
    cmd="${words[$i]}"
    [[ "$cmd" == "apt-get" || "$cmd" == "apt" ]] || continue
    rest=("${words[@]:$((i + 1))}")
    is_install=0 norec=0 pkgs=()
    for w in "${rest[@]}"; do
      case "$w" in
        install) is_install=1 ;;
        --no-install-recommends) norec=1 ;;
        -o) ;;
        -*) ;;
        *) [ $is_install -eq 1 ] && [[ "$w" != *=* || "$w" =~ ^[a-z0-9][a-z0-9.+-]*= ]] && pkgs+=("$w") ;;
      esac
    done
    [ $is_install -eq 1 ] || continue
    installs=$((installs + 1))
    [ $norec -eq 1 ] || fail "an apt install in the runtime stage without --no-install-recommends: $seg"
    for p in "${pkgs[@]}"; do
      p="${p%%=*}"
      RUNTIME_PACKAGES+=("${p%%:*}")
    done
  done <<< "$segments"
done < <(printf '%s\n' "$RT" | grep -iE '^RUN[[:space:]]' || true)
if [ $installs -eq 0 ] || [ ${#RUNTIME_PACKAGES[@]} -eq 0 ]; then
  fail "found no apt-get install in the runtime stage"
else
  ok "${#RUNTIME_PACKAGES[@]} runtime packages: ${RUNTIME_PACKAGES[*]}"
fi

for p in "${RUNTIME_PACKAGES[@]}"; do
  [[ "$p" =~ $FORBIDDEN ]] && fail "the runtime stage installs $p (a compiler or build tool, Chromium, Node/npm or a -dev package)"
done

# Other ways in: the project's install script, language package managers, downloads, local .debs.
others="$(printf '%s\n' "$RT" | grep -iE '^(RUN|ADD)[[:space:]]' \
  | grep -nE '(^ADD[[:space:]])|install_deps|(^|[^a-z-])(npm|npx|node|pip3?|curl|wget|gcc|g\+\+|cc|c\+\+|clang|cmake|ninja|make)([[:space:]]|$)|dpkg[[:space:]]+-i' || true)"
if [ -z "$others" ]; then
  ok "no other installer, download or compiler in the runtime stage's RUN/ADD"
else
  fail "the runtime stage's RUN/ADD name an installer, a download or a compiler: $others"
fi

# Every listed package exists in Debian 12 (a typo would stop docker build, which nobody runs here),
# and nothing forbidden comes along as a Depends (Recommends are refused above). apt-cache is slow
# to start, so each question is asked for all packages at once.
APT_DEPENDS=(apt-cache depends --no-recommends --no-suggests --no-conflicts --no-breaks --no-replaces --no-enhances)
if ! apt-cache show --no-all-versions libc6 > /dev/null 2>&1; then
  fail "apt-cache knows no package (run apt-get update): cannot check the runtime packages against Debian 12"
else
  known=" $(apt-cache show --no-all-versions "${RUNTIME_PACKAGES[@]}" 2> /dev/null | sed -n 's/^Package: //p' | tr '\n' ' ') "
  for p in "${RUNTIME_PACKAGES[@]}"; do
    [[ "$known" == *" $p "* ]] || fail "$p: no such package in this machine's Debian 12 lists"
  done
  closure="$("${APT_DEPENDS[@]}" --recurse "${RUNTIME_PACKAGES[@]}" 2> /dev/null | grep -v '^ ' | sed 's/:.*//' | sort -u)"
  bad="$(printf '%s\n' "$closure" | grep -E "$FORBIDDEN" | grep -v '^<' || true)"
  if [ -n "$bad" ]; then
    fail "the runtime packages' Depends (alternatives included) bring in: $(printf '%s' "$bad" | tr '\n' ' ')"
  else
    ok "their Depends ($(printf '%s\n' "$closure" | grep -vc '^<') packages, alternatives included) hold no compiler, build tool, Chromium, Node or -dev package"
  fi
  # The base set: hard dependencies of apt (of alternatives only the first), which every Debian
  # image has. Breadth first, one apt-cache call per level.
  apt_deps=" apt "
  queue=(apt)
  while [ ${#queue[@]} -gt 0 ]; do
    next=()
    in_alt=0
    while IFS= read -r line; do
      case "$line" in
        " |Depends: "* | " |PreDepends: "*)
          [ $in_alt -eq 0 ] || continue
          in_alt=1
          d="${line#*: }"
          ;;
        "  Depends: "* | "  PreDepends: "*)
          if [ $in_alt -eq 1 ]; then
            in_alt=0
            continue
          fi
          d="${line#*: }"
          ;;
        " "*) continue ;;
        *)
          in_alt=0
          continue
          ;;
      esac
      d="${d%%:*}"
      [[ "$d" != "<"* ]] || continue
      [[ "$apt_deps" != *" $d "* ]] || continue
      apt_deps+="$d "
      next+=("$d")
    done < <("${APT_DEPENDS[@]}" "${queue[@]}" 2> /dev/null)
    queue=("${next[@]+"${next[@]}"}")
  done
  base_ok=1
  for b in "${BASE_PACKAGES[@]}"; do
    if [[ "$apt_deps" != *" $b "* ]]; then
      fail "base package $b is not a hard dependency of apt: list it in the runtime stage"
      base_ok=0
    fi
  done
  [ $base_ok -eq 0 ] || ok "base set (${BASE_PACKAGES[*]}): hard dependencies of apt, so in every debian:12-slim"
fi

echo "== 2. the runtime packages against ldd of $BUILD's binaries"
# Each binary's libraries as ldd resolves them (the loader included).
declare -A libs_of=()
all_libs=()
for bin in "${BINARIES[@]}"; do
  if [ ! -x "$bin" ]; then
    fail "no $bin (build it first: the check reads its dynamic libraries)"
    continue
  fi
  if ! lddout="$(ldd "$bin" 2>&1)"; then
    fail "ldd $bin: $lddout"
    continue
  fi
  missing="$(printf '%s\n' "$lddout" | grep 'not found' || true)"
  [ -z "$missing" ] || fail "$bin: libraries not found here: $missing"
  libs_of[$bin]="$(printf '%s\n' "$lddout" | awk '$2 == "=>" && $3 ~ /^\// { print $3 } $1 ~ /^\// { print $1 }' | sort -u)"
  mapfile -t -O "${#all_libs[@]}" all_libs <<< "${libs_of[$bin]}"
  ok "$bin: $(printf '%s\n' "${libs_of[$bin]}" | grep -c .) libraries resolved"
done
# The package owning each: dpkg registers /lib/... or /usr/lib/... (merged /usr), so every
# spelling of the path and of its target is looked up, in dpkg's file lists at once (what
# `dpkg -S` reads, and as slow there as the number of paths given).
declare -A owner_of_path=()
declare -A candidates_of=()
queries=""
for lib in "${all_libs[@]}"; do
  [ -n "$lib" ] || continue
  c=""
  for t in "$lib" "$(readlink -f "$lib")"; do
    for v in "$t" "${t#/usr}" "/usr$t"; do
      [[ " $c " == *" $v "* ]] || c+="$v "
    done
  done
  candidates_of[$lib]="$c"
  queries+="${c// /$'\n'}"
done
if [ -n "$queries" ]; then
  while IFS= read -r line; do
    list="${line%%.list:/*}"
    pkg="${list##*/}"
    path="${line#*.list:}"
    owner_of_path[$path]+="${pkg%%:*} "
  done < <(grep -H -F -x -f <(printf '%s' "$queries") /var/lib/dpkg/info/*.list 2> /dev/null || true)
fi
declare -A used=()
for bin in "${BINARIES[@]}"; do
  [ -n "${libs_of[$bin]:-}" ] || continue
  while IFS= read -r lib; do
    owners=""
    for c in ${candidates_of[$lib]}; do
      if [ -n "${owner_of_path[$c]:-}" ]; then
        owners="${owner_of_path[$c]}"
        break
      fi
    done
    if [ -z "$owners" ]; then
      fail "$bin: $lib belongs to no Debian package (installed by hand?): the runtime stage could not install it"
      continue
    fi
    covered=""
    for p in $owners; do
      for r in "${RUNTIME_PACKAGES[@]}" "${BASE_PACKAGES[@]}"; do
        if [ "$p" = "$r" ]; then
          covered="$p"
          used[$p]=1
        fi
      done
    done
    [ -n "$covered" ] || fail "$bin needs $lib from ${owners% }, which the runtime stage does not install"
  done <<< "${libs_of[$bin]}"
done
for p in "${RUNTIME_PACKAGES[@]}"; do
  [ -n "${used[$p]:-}" ] || fail "the runtime stage installs $p, which owns none of the binaries' libraries (not needed: remove it)"
done
if [ ${#used[@]} -gt 0 ]; then
  ok "every library covered; the packages they come from: $(printf '%s\n' "${!used[@]}" | sort | tr '\n' ' ')"
fi

echo "== 3. user, health check, entrypoint, what is copied in"
last_user="$(printf '%s\n' "$RT" | awk 'toupper($1) == "USER" { u = $2 } END { print u }')"
user_part="${last_user%%:*}"
if [ -z "$last_user" ]; then
  fail "the runtime stage sets no USER: it would run as root"
elif [ "$user_part" = "root" ] || [[ "$user_part" =~ ^0+$ ]]; then
  fail "USER $last_user is root"
else
  ok "USER $last_user"
fi
# COPY: from the build stage only the two binaries; from the context only docker/ files.
copied=" "
while IFS= read -r line; do
  read -r -a w <<< "$line"
  from=""
  args=()
  for x in "${w[@]:1}"; do
    case "$x" in
      --from=*) from="${x#--from=}" ;;
      --*) ;;
      *) args+=("$x") ;;
    esac
  done
  [ ${#args[@]} -ge 2 ] || { fail "cannot read: $line"; continue; }
  dest="${args[-1]}"
  for src in "${args[@]:0:${#args[@]}-1}"; do
    if [ -n "$from" ]; then
      case "$(basename "$src")" in
        gatekeeperd | gatekeeper-cli) ;;
        *) fail "the runtime stage copies $src from stage $from: only gatekeeperd and gatekeeper-cli belong there" ;;
      esac
    else
      [[ "$src" == docker/* && -f "$src" ]] || fail "the runtime stage copies $src from the context: only files under docker/ belong there"
    fi
    if [[ "$dest" == */ ]]; then copied+="$dest$(basename "$src") "; else copied+="$dest "; fi
  done
done < <(printf '%s\n' "$RT" | grep -iE '^COPY[[:space:]]' || true)
if [[ "$copied" == *"/gatekeeperd "* && "$copied" == *"/gatekeeper-cli "* ]]; then
  ok "copied in:$copied"
else
  fail "the runtime stage does not copy in both gatekeeperd and gatekeeper-cli (copies:$copied)"
fi
# The program an exec-form instruction (HEALTHCHECK CMD / ENTRYPOINT) starts, when copied in.
names_copied() {
  local prog
  prog="$(printf '%s\n' "$1" | sed -nE 's/.*\[[[:space:]]*"([^"]+)".*/\1/p')"
  [ -n "$prog" ] && [[ "$copied" == *" $prog "* ]]
}
hc="$(printf '%s\n' "$RT" | grep -iE '^HEALTHCHECK[[:space:]]' | tail -1 || true)"
if [ -z "$hc" ] || [[ "${hc^^}" =~ ^HEALTHCHECK[[:space:]]+NONE ]]; then
  fail "the runtime stage has no HEALTHCHECK"
elif ! names_copied "${hc#*CMD}"; then
  fail "HEALTHCHECK does not run (exec form) a file the runtime stage copies in: $hc"
else
  ok "$hc"
fi
ep="$(printf '%s\n' "$RT" | grep -iE '^ENTRYPOINT[[:space:]]' | tail -1 || true)"
if [ -z "$ep" ] || ! names_copied "$ep"; then
  fail "the runtime stage has no ENTRYPOINT (exec form) running a file it copies in: $ep"
else
  ok "$ep"
fi
if printf '%s\n' "$RT" | grep -qiE '^VOLUME[[:space:]].*/data'; then
  ok "VOLUME /data"
else
  fail "no VOLUME /data in the runtime stage"
fi

echo "== 4. the container's scripts"
for s in "$ENTRYPOINT_SH" "$HEALTHCHECK_SH"; do
  if [ ! -f "$s" ]; then
    fail "no $s"
    continue
  fi
  head -1 "$s" | grep -qx '#!/bin/bash' || fail "$s: first line is not #!/bin/bash (bash is in debian:12-slim, at /bin/bash)"
  if err="$(bash -n "$s" 2>&1)"; then ok "bash -n $s"; else fail "bash -n $s: $err"; fi
  if command -v shellcheck > /dev/null; then
    if err="$(shellcheck -s bash "$s" 2>&1)"; then ok "shellcheck $s"; else fail "shellcheck $s:"$'\n'"$err"; fi
  else
    echo "note: shellcheck is not installed: $s only had bash -n"
  fi
done

echo "== 5. the entrypoint and health check on $BUILD's binaries, mode by mode"
# As in the image: the two binaries and the two scripts under their image names in one PATH.
work="$(mktemp -d /tmp/check_container.XXXXXX)"
daemon_pid=""
cleanup() {
  [ -z "$daemon_pid" ] || kill -TERM "$daemon_pid" 2> /dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
if [ ! -x "${BINARIES[0]}" ] || [ ! -x "${BINARIES[1]}" ] || ! command -v openssl > /dev/null; then
  fail "cannot run the scripts: the binaries or the openssl command are missing"
else
  mkdir -p "$work/bin" "$work/pki"
  cp "${BINARIES[@]}" "$work/bin/"
  cp "$ENTRYPOINT_SH" "$work/bin/gatekeeper-entrypoint"
  cp "$HEALTHCHECK_SH" "$work/bin/gatekeeper-healthcheck"
  chmod 0755 "$work" "$work/bin" "$work/bin"/*
  # A CA, a server certificate for a name other than 127.0.0.1, a client certificate of the CA.
  (
    cd "$work/pki"
    openssl req -x509 -newkey rsa:2048 -nodes -keyout ca.key -out ca.pem -days 2 -subj /CN=check-ca
    openssl req -newkey rsa:2048 -nodes -keyout server.key -out server.csr -subj /CN=gatekeeper.test
    printf 'subjectAltName=DNS:gatekeeper.test\n' > server.ext
    openssl x509 -req -in server.csr -CA ca.pem -CAkey ca.key -CAcreateserial -out server.pem -days 2 -extfile server.ext
    openssl req -newkey rsa:2048 -nodes -keyout client.key -out client.csr -subj /CN=health
    openssl x509 -req -in client.csr -CA ca.pem -CAkey ca.key -CAcreateserial -out client.pem -days 2
  ) > "$work/pki.log" 2>&1 || fail "openssl: $(cat "$work/pki.log")"
  if [ "$(id -u)" -eq 0 ]; then
    as_user=(setpriv --reuid 10001 --regid 10001 --clear-groups)
    owner_id=10001
  else
    as_user=()
    owner_id="$(id -u)"
  fi
  # mode NAME EXPECT(healthy|refused) FILES... [-- DAEMON ARGS]: set up /etc/gatekeeper's stand-in
  # with FILES, start the entrypoint, run the health check, stop gatekeeperd with SIGTERM.
  mode() {
    local name="$1" expect="$2" root="$work/$1" i hc rc
    shift 2
    mkdir -p "$root/conf" "$root/data" "$root/tmp"
    while [ $# -gt 0 ] && [ "$1" != "--" ]; do
      case "$1" in
        server) cp "$work/pki/server.pem" "$work/pki/server.key" "$root/conf/" ;;
        client-ca) cp "$work/pki/ca.pem" "$root/conf/client-ca.pem" ;;
        health-ca) cp "$work/pki/ca.pem" "$root/conf/health-ca.pem" ;;
        health-client)
          cp "$work/pki/client.pem" "$root/conf/health-client.pem"
          cp "$work/pki/client.key" "$root/conf/health-client.key"
          ;;
        tokens) printf '# role token\nadmin check-admin-token-0123456789\nread check-read-token-0123456789\n' > "$root/conf/tokens" ;;
      esac
      shift
    done
    [ "${1:-}" != "--" ] || shift
    chmod 0600 "$root/conf"/* 2> /dev/null || true
    chown -R "$owner_id:$owner_id" "$root"
    local env=(env "PATH=$work/bin:/usr/bin:/bin" "GATEKEEPER_CONFIG_DIR=$root/conf" "GATEKEEPER_DATA_DIR=$root/data"
      "GATEKEEPER_PORT=0" "GATEKEEPER_PORT_FILE=$root/tmp/port" "GATEKEEPER_TLS_SERVER_NAME=gatekeeper.test"
      "GATEKEEPER_METRICS_PORT=0" "GATEKEEPER_METRICS_PORT_FILE=$root/tmp/metrics-port")
    "${as_user[@]}" "${env[@]}" gatekeeper-entrypoint --drain-seconds 1 --log-level warn "$@" > "$root/log" 2>&1 &
    daemon_pid=$!
    for i in $(seq 1 150); do
      [ -s "$root/tmp/port" ] && break
      kill -0 "$daemon_pid" 2> /dev/null || break
      sleep 0.1
    done
    if [ "$expect" = refused ]; then
      if kill -0 "$daemon_pid" 2> /dev/null; then
        fail "$name: started, but should have been refused"
        kill -TERM "$daemon_pid" 2> /dev/null || true
        wait "$daemon_pid" || true
      else
        rc=0
        wait "$daemon_pid" || rc=$?
        if [ $rc -ne 0 ]; then
          ok "$name: refused (exit $rc): $(tail -1 "$root/log")"
        else
          fail "$name: exited 0, should have been refused"
        fi
      fi
      daemon_pid=""
      return
    fi
    if ! [ -s "$root/tmp/port" ]; then
      fail "$name: gatekeeperd did not start: $(cat "$root/log")"
      daemon_pid=""
      return
    fi
    rc=0
    hc="$("${as_user[@]}" "${env[@]}" gatekeeper-healthcheck 2>&1)" || rc=$?
    # /metrics on the container's loopback, from the port the entrypoint asked for.
    if [ -s "$root/tmp/metrics-port" ] &&
      python3 -c 'import sys, urllib.request; sys.exit(0 if b"gatekeeper_rpc_calls_total" in urllib.request.urlopen(sys.argv[1], timeout=10).read() else 1)' \
        "http://127.0.0.1:$(cat "$root/tmp/metrics-port")/metrics"; then
      hc="$hc; /metrics served"
    else
      fail "$name: no /metrics on the container's loopback"
    fi
    if [ $rc -eq 0 ]; then
      ok "$name: $(head -1 "$root/log" | sed 's/^gatekeeper-entrypoint: //'); $hc"
    else
      fail "$name: health check: $hc"
    fi
    kill -TERM "$daemon_pid" 2> /dev/null || true
    rc=0
    wait "$daemon_pid" || rc=$?
    daemon_pid=""
    [ $rc -eq 0 ] || fail "$name: gatekeeperd exited $rc on SIGTERM: $(tail -3 "$root/log")"
    rc=0
    hc="$("${as_user[@]}" "${env[@]}" gatekeeper-healthcheck 2>&1)" || rc=$?
    [ $rc -ne 0 ] || fail "$name: the health check still passes once gatekeeperd has stopped: $hc"
  }
  mode loopback healthy
  mode loopback-tokens healthy tokens
  mode tls-tokens-listening healthy server tokens
  mode tls-tokens-call healthy server tokens health-ca
  mode mutual-tls-call healthy server client-ca health-ca health-client
  mode tls-alone refused server
  mode tls-beyond-loopback-refused refused -- --listen 0.0.0.0:0
fi

echo
if [ $failures -gt 0 ]; then
  echo "check_container: $failures failure(s)"
  exit 1
fi
echo "check_container: all checks passed (the image itself was not built: no Docker engine here)"
