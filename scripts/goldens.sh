#!/usr/bin/env bash
# Re-records every golden's sequence with ISPM and replays it against the golden: each must be
# bit-exact in every buffer of every frame (report.json counts: nothing but "bit-exact"). The
# check that a change which should move no bit moves none.
# usage: scripts/goldens.sh [ISPM] [WORK_DIR]   (defaults: build/cli/ispm, a temporary folder)
# Prints one line per golden and a total; exits 1 when any golden is not bit-exact.
set -u
cd "$(dirname "$0")/.."
ISPM=${1:-build/cli/ispm}
WORK=${2:-$(mktemp -d)}
mkdir -p "$WORK"
bad=0; n=0
for g in golden/*/; do
  g=${g%/}; name=$(basename "$g")
  [ -f "$g/manifest.json" ] || continue   # golden/objects/: the shared object store
  seq=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["sequence"]["path"])' "$g/manifest.json")
  n=$((n + 1))
  rm -rf "$WORK/$name"
  if ! "$ISPM" record "$seq" -o "$WORK/$name" --quiet > "$WORK/$name.log" 2>&1; then
    echo "FAIL $name: record exited non-zero ($WORK/$name.log)"; bad=$((bad + 1)); continue
  fi
  "$ISPM" replay "$WORK/$name" --golden "$g" --quiet > /dev/null 2>&1
  verdict=$(python3 - "$WORK/$name/replay/report.json" <<'PY'
import json, sys
try:
    r = json.load(open(sys.argv[1]))
except (OSError, ValueError) as e:
    print("no report: %s" % e); sys.exit()
c = r["counts"]; other = {k: v for k, v in c.items() if k != "bit-exact" and v}
print("bit-exact %d buffers" % c["bit-exact"] if not other and c["bit-exact"] else "NOT bit-exact %s" % c)
PY
)
  case $verdict in bit-exact*) echo "ok   $name: $verdict" ;; *) echo "FAIL $name: $verdict"; bad=$((bad + 1)) ;; esac
done
echo "goldens: $((n - bad)) of $n bit-exact"
[ $bad -eq 0 ]
