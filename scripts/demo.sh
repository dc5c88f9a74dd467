#!/usr/bin/env bash
# The main job: set up, build, record the default sequence (the animated Cornell box, CI size) and
# replay it against its golden. Prints where the run and the report are; exits with
# replay's code (0 ok, 1 warnings, 2 failures, 3 size mismatch, 4 unreadable).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
SEQ=${1:-scenes/cornell-box/cornell-box-ci.json}
NAME=$(basename "$SEQ" .json)
RUN=${RUN:-runs/$NAME}
./build/cli/ispm record "$SEQ" -o "$RUN" --force
set +e
./build/cli/ispm replay "$RUN" --golden "golden/$NAME"
rc=$?
set -e
echo "run:    $RUN"
echo "report: $RUN/replay/report.html (and report.txt, report.json, report.junit.xml)"
exit $rc
