#!/usr/bin/env bash
# Runs a bench command and writes its output as a dated record of the manual, with what makes a
# figure comparable: the command, its exit status, the commit and binary version, the machine
# (CPU model, cores, memory, OS, load average) and the Mesa and Embree packages.
# usage: bench/record.sh NAME -- COMMAND [ARG...]
#   writes docs/measurements/records/NAME.md (RECORD_DIR overrides the folder) and exits with
#   the command's status. NAME: letters, digits, '.', '_' and '-'.
set -u
cd "$(dirname "$0")/.."
[ $# -ge 3 ] && [ "$2" = "--" ] || { echo "usage: bench/record.sh NAME -- COMMAND [ARG...]" >&2; exit 2; }
NAME=$1; shift 2
[[ "$NAME" =~ ^[A-Za-z0-9][A-Za-z0-9._-]*$ ]] || { echo "bench/record.sh: bad record name '$NAME'" >&2; exit 2; }
DIR=${RECORD_DIR:-docs/measurements/records}
mkdir -p "$DIR"
OUT="$DIR/$NAME.md"
TMP=$(mktemp)
start=$(date -u '+%Y-%m-%d %H:%M UTC')
load=$(cut -d' ' -f1-3 /proc/loadavg)
"$@" > "$TMP" 2>&1
rc=$?
pkg() { dpkg-query -W -f='${Package} ${Version}' "$1" 2>/dev/null || echo "$1 (not installed)"; }
{
  echo "# $NAME"
  echo
  echo "- date: $start"
  printf -- '- command: `%s`\n' "$*"
  echo "- exit status: $rc"
  echo "- commit: $(git rev-parse --short=12 HEAD 2>/dev/null || echo unknown)$(git diff --quiet HEAD 2>/dev/null || echo ' (with uncommitted changes)')"
  [ -x build/cli/ispm ] && echo "- binary: $(build/cli/ispm --version 2>/dev/null | head -1)"
  echo "- CPU: $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -1), $(nproc) cores"
  echo "- memory: $(awk '/^MemTotal/ {printf "%.1f GiB", $2 / 1048576}' /proc/meminfo)"
  echo "- OS: $(. /etc/os-release 2>/dev/null && echo "$PRETTY_NAME"), kernel $(uname -r)"
  echo "- load average at the start: $load"
  echo "- packages: $(pkg libgl1-mesa-dri), $(pkg libembree3-3)"
  echo
  echo '```'
  cat "$TMP"
  echo '```'
} > "$OUT"
rm -f "$TMP"
echo "record: $OUT"
exit $rc
