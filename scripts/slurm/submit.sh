#!/usr/bin/env bash
# Records SEQUENCE as N shards on Slurm, merges them and (with GOLDEN) replays the run:
#   scripts/slurm/submit.sh SEQUENCE OUTDIR N [GOLDEN] [-- sbatch options for every job]
# Prints the three job ids ("shards=ID merge=ID replay=ID"); the run is OUTDIR/run. Submit
# from the repository root (or set ISPM to the binary's absolute path).
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: submit.sh SEQUENCE OUTDIR N [GOLDEN] [-- sbatch options]" >&2; exit 2; }
SEQ=$1 OUT=$2 N=$3; shift 3
GOLDEN=""
if [ $# -gt 0 ] && [ "$1" != "--" ]; then GOLDEN=$1; shift; fi
[ $# -gt 0 ] && [ "$1" = "--" ] && shift
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
arr=$(sbatch --parsable "$@" --array=0-$((N - 1)) -o "$OUT/shard-%a.log" "$HERE/shard.sbatch" "$SEQ" "$OUT")
arr=${arr%%;*}
merge=$(sbatch --parsable "$@" --dependency=afterok:"$arr" -o "$OUT/merge.log" "$HERE/merge.sbatch" "$OUT" "$N")
merge=${merge%%;*}
replay=""
if [ -n "$GOLDEN" ]; then
  replay=$(sbatch --parsable "$@" --dependency=afterok:"$merge" -o "$OUT/replay.log" "$HERE/replay.sbatch" "$OUT" "$GOLDEN")
  replay=${replay%%;*}
fi
echo "shards=$arr merge=$merge replay=$replay"
