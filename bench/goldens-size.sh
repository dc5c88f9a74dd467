#!/bin/sh
# bench/goldens-size.sh — what goldens and runs cost to store (docs/goldens.md), four figures:
#
#   1. bytes of golden/: in all, the object store, the goldens still in frame files; goal ≤ 70 MB
#   2. bytes a rebless adds to git: a scratch repository holding golden/cornell-box-ci, once as
#      frame files (format 1) and once migrated to a store (format 2); kernel_radius 0.15 → 0.16,
#      ispm bless --accept, commit; the blobs the commit adds, against the golden's bytes
#                                                                           goal ≤ 30 % (format 2)
#   3. the atrium at 1920×1080, 3 frames: bytes per frame, parts held, record wall and CPU time, all buffers vs
#      final.display only, alternated ATRIUM_RUNS times (default 1, at most 2: it is slow)
#                                                                           goals ≤ 154 MB, ≤ 1.25×
#   4. replay of a cornell-box-ci run against the golden as objects vs the same golden as frame
#      files (ispm golden unpack), with idiff -a over the same EXR pairs as in bench/perf.sh,
#      alternated RUNS times (default 3)                                   goal: objects ≤ 1.0× files
#   5. (only when ROWS names it) what codecs make of the objects: ZIP level 9 as stored, PIZ and
#      no compression through oiiotool, and xz -9e over the uncompressed EXR, on every
#      SAMPLE-th object in name order (default 7): how far lossless storage can shrink golden/
#
# usage: bench/goldens-size.sh [OUTDIR]   (from the repository root; ISPM=path/to/ispm,
#        ROWS=1234 picks rows, RUNS=N, ATRIUM_RUNS=N, COMPRESSION=none|zip|piz|... for row 3)
# Everything it writes goes to OUTDIR (default: a fresh folder under /tmp).
set -eu

ISPM=${ISPM:-build/cli/ispm}
RUNS=${RUNS:-3}
ATRIUM_RUNS=${ATRIUM_RUNS:-1}
ROWS=${ROWS:-1234}
SAMPLE=${SAMPLE:-7}
COMPRESSION=${COMPRESSION:-}
OUT=${1:-$(mktemp -d /tmp/ispm-goldens-size.XXXXXX)}
TOP=$(pwd)
[ -x "$ISPM" ] || { echo "goldens-size.sh: $ISPM not built (cmake --build build)" >&2; exit 2; }
ISPM=$(cd "$(dirname "$ISPM")" && pwd)/$(basename "$ISPM")
mkdir -p "$OUT"
. "$(dirname "$0")/timing.sh" # now, median, ratio

mb() { awk -v b="$1" 'BEGIN { printf "%.2f MB", b / 1e6 }'; }
bytes() { du -sb "$@" | awk '{ s += $1 } END { print s + 0 }'; }
# seq_with SRC DST KEY=VALUE...: a copy of sequence SRC whose scene path is absolute, with
# settings (or top-level "resolution", "frames", "capture") changed: KEY=JSON.
seq_with() {
    python3 - "$@" <<'PY'
import json, os, sys
src, dst = sys.argv[1], sys.argv[2]
s = json.load(open(src))
s["scene"] = os.path.join(os.path.dirname(os.path.abspath(src)), s["scene"])
for kv in sys.argv[3:]:
    k, v = kv.split("=", 1)
    (s if k in ("resolution", "frames", "capture") else s["settings"])[k] = json.loads(v)
json.dump(s, open(dst, "w"), indent=1)
PY
}

if echo "$ROWS" | grep -q 1; then
    echo "1. golden/"
    all=$(bytes golden)
    store=$( [ -d golden/objects ] && bytes golden/objects || echo 0)
    f1=0 n1=0 n2=0
    for m in golden/*/manifest.json; do
        g=$(dirname "$m")
        if grep -q '"format_version":[[:space:]]*2' "$m"; then n2=$((n2 + 1)); else n1=$((n1 + 1)); f1=$((f1 + $(bytes "$g"))); fi
    done
    printf '  golden/ %s: objects %s (%s goldens of format 2), frame-file goldens %s (%s of format 1); goal <= 70 MB\n' \
        "$(mb "$all")" "$(mb "$store")" "$n2" "$(mb "$f1")" "$n1"
fi

if echo "$ROWS" | grep -q 2; then
    echo "2. rebless of cornell-box-ci, kernel_radius 0.15 -> 0.16"
    seq_with scenes/cornell-box/cornell-box-ci.json "$OUT/ci.json"
    seq_with scenes/cornell-box/cornell-box-ci.json "$OUT/ci-016.json" kernel_radius=0.16
    "$ISPM" record "$OUT/ci-016.json" -o "$OUT/run-016" --force --quiet > "$OUT/record-016.log" 2>&1
    for fmt in 1 2; do
        R=$OUT/scratch-$fmt
        rm -rf "$R"; mkdir -p "$R/golden"
        if grep -q '"format_version":[[:space:]]*2' golden/cornell-box-ci/manifest.json; then
            "$ISPM" golden unpack golden/cornell-box-ci "$R/golden/cornell-box-ci" > /dev/null
        else
            cp -r golden/cornell-box-ci "$R/golden/"
        fi
        if [ "$fmt" = 2 ]; then mkdir "$R/golden/objects"; "$ISPM" golden migrate "$R/golden/cornell-box-ci" > /dev/null; fi
        git -C "$R" init -q; git -C "$R" add -A; git -C "$R" -c user.name=b -c user.email=b@b commit -qm golden
        before=$(git -C "$R" ls-tree -r -l HEAD | awk '{ s += $4 } END { print s }')
        "$ISPM" bless "$OUT/run-016" "$R/golden/cornell-box-ci" --accept --review "$OUT/review-$fmt" > "$OUT/bless-$fmt.log" 2>&1
        git -C "$R" add -A; git -C "$R" -c user.name=b -c user.email=b@b commit -qm rebless
        added=$(git -C "$R" diff-tree -r --no-renames HEAD~1 HEAD | awk '$5 != "D" { print $4 }' |
                while read -r h; do git -C "$R" cat-file -s "$h"; done | awk '{ s += $1 } END { print s + 0 }')
        changed=$(git -C "$R" diff-tree -r --no-renames HEAD~1 HEAD | awk '$5 != "D"' | wc -l)
        printf '  format %s: golden %s in git, the rebless adds %s in %s blobs = %s %% of it\n' "$fmt" "$(mb "$before")" \
            "$(mb "$added")" "$changed" "$(awk -v a="$added" -v b="$before" 'BEGIN { printf "%.1f", 100 * a / b }')"
    done
    echo "  goal: format 2 <= 30 %"
fi

if echo "$ROWS" | grep -q 3; then
    echo "3. atrium 1920x1080, 3 frames, all buffers vs final.display only ($ATRIUM_RUNS alternation(s))"
    extra=""
    [ -n "$COMPRESSION" ] && extra="capture_compression=\"$COMPRESSION\""
    # shellcheck disable=SC2086
    seq_with scenes/atrium/atrium-640x480.json "$OUT/atrium-all.json" resolution='[1920,1080]' frames=3 $extra
    # shellcheck disable=SC2086
    seq_with scenes/atrium/atrium-640x480.json "$OUT/atrium-final.json" resolution='[1920,1080]' frames=3 \
        capture='["final.display"]' $extra
    # Wall time, and CPU (user + sys of the record, /usr/bin/time), which a machine shared with
    # other work distorts less.
    ta="" tb="" ca="" cb="" i=0
    while [ "$i" -lt "$ATRIUM_RUNS" ]; do
        for side in all final; do
            rm -rf "$OUT/atrium-$side"
            s=$(now)
            /usr/bin/time -f '%U %S' -o "$OUT/atrium-$side.cpu" \
                "$ISPM" record "$OUT/atrium-$side.json" -o "$OUT/atrium-$side" --quiet > "$OUT/atrium-$side.log" 2>&1
            e=$(now)
            t=$(awk -v s="$s" -v e="$e" 'BEGIN { printf "%.2f", e - s }')
            c=$(awk 'END { printf "%.2f", $1 + $2 }' "$OUT/atrium-$side.cpu")
            if [ "$side" = all ]; then ta="$ta $t" ca="$ca $c"; else tb="$tb $t" cb="$cb $c"; fi
        done
        i=$((i + 1))
    done
    per=$(( $(bytes "$OUT/atrium-all/frames") / 3 ))
    A=$(echo "$ta" | median) B=$(echo "$tb" | median) CA=$(echo "$ca" | median) CB=$(echo "$cb" | median)
    held=0
    for f in "$OUT"/atrium-all/frames/*.exr; do
        held=$((held + $(oiiotool --info "$f" 2> /dev/null | sed -n 's/.*(\([0-9]*\) subimages).*/\1/p;t;q' | grep . || echo 1)))
    done
    printf '  all buffers: %s per frame (%s parts in the frame files, %s buffers), record %s s, CPU %s s (runs:%s; CPU:%s)\n' \
        "$(mb "$per")" "$held" "$(grep -o '"first_nonfinite"' "$OUT/atrium-all/manifest.json" | wc -l)" "$A" "$CA" "$ta" "$ca"
    printf '  final.display only: record %s s, CPU %s s (runs:%s; CPU:%s)\n' "$B" "$CB" "$tb" "$cb"
    printf '  ratio all / final.display: %sx wall, %sx CPU; goals <= 154 MB per frame, <= 1.25x\n' \
        "$(ratio "$A" "$B")" "$(ratio "$CA" "$CB")"
    rm -rf "$OUT/atrium-all" "$OUT/atrium-final"
fi

if echo "$ROWS" | grep -q 4; then
    echo "4. replay of a cornell-box-ci run: golden as objects vs as frame files, idiff -a ($RUNS alternations)"
    [ -d "$OUT/run" ] || { seq_with scenes/cornell-box/cornell-box-ci.json "$OUT/ci.json";
        "$ISPM" record "$OUT/ci.json" -o "$OUT/run" --force --quiet > "$OUT/record.log" 2>&1; }
    G=$OUT/g4; rm -rf "$G"; mkdir -p "$G/objects"
    if grep -q '"format_version":[[:space:]]*2' golden/cornell-box-ci/manifest.json; then
        "$ISPM" golden unpack golden/cornell-box-ci "$G/files" > /dev/null
    else
        cp -r golden/cornell-box-ci "$G/files"
    fi
    cp -r "$G/files" "$G/objs"; "$ISPM" golden migrate "$G/objs" > /dev/null
    # idiff reads whole frame files: the run's frame files hold only the buffers that changed
    # since the frame before, so its frames are written out whole with ispm export.
    rm -rf "$OUT/run-whole"; mkdir -p "$OUT/run-whole"
    for f in "$OUT/run/frames/"*.exr; do
        n=$(basename "$f" .exr)
        "$ISPM" export "$OUT/run" --frame "$(echo "$n" | sed 's/^0*//; s/^$/0/')" -o "$OUT/run-whole/$n.exr" > /dev/null
    done
    # timed CMD...: appends "wall cpu" (seconds; CPU = user + system of the command) to $OUT/t
    timed() { /usr/bin/time -f "%e %U %S" -o "$OUT/t1" "$@" > /dev/null 2>&1 || true; tail -n 1 "$OUT/t1" | awk '{ printf "%s %.2f\n", $1, $2 + $3 }'; }
    to="" tf="" ti="" co="" cf="" i=0
    while [ "$i" -lt "$RUNS" ]; do
        x=$(timed "$ISPM" replay "$OUT/run" --golden "$G/objs" --report "$OUT/rep-o" --quiet); to="$to ${x% *}" co="$co ${x#* }"
        x=$(timed "$ISPM" replay "$OUT/run" --golden "$G/files" --report "$OUT/rep-f" --quiet); tf="$tf ${x% *}" cf="$cf ${x#* }"
        if command -v idiff > /dev/null; then
            s=$(now)
            for f in "$OUT/run-whole/"*.exr; do idiff -a "$f" "$G/files/frames/$(basename "$f")" > /dev/null 2>&1 || true; done
            e=$(now)
            ti="$ti $(awk -v s="$s" -v e="$e" 'BEGIN { printf "%.3f", e - s }')"
        fi
        i=$((i + 1))
    done
    O=$(echo "$to" | median) F=$(echo "$tf" | median)
    printf '  replay vs golden as objects:     %s s (runs:%s; CPU %s s)\n' "$O" "$to" "$(echo "$co" | median)"
    printf '  replay vs golden as frame files: %s s (runs:%s; CPU %s s)\n' "$F" "$tf" "$(echo "$cf" | median)"
    [ -n "$ti" ] && printf '  idiff -a over the same pairs:    %s s (runs:%s)\n' "$(echo "$ti" | median)" "$ti"
    printf '  objects / frame files: %sx (goal <= 1.0x: no slower)\n' "$(ratio "$O" "$F")"
fi
if echo "$ROWS" | grep -q 5; then
    echo "5. the objects under other codecs (every ${SAMPLE}th object of golden/objects)"
    command -v oiiotool > /dev/null && command -v xz > /dev/null ||
        { echo "goldens-size.sh: row 5 needs oiiotool and xz" >&2; exit 2; }
    z=0 p=0 n=0 x=0 k=0 i=0
    for f in $(find golden/objects -name '*.exr' | LC_ALL=C sort); do
        i=$((i + 1))
        [ $(((i - 1) % SAMPLE)) -eq 0 ] || continue
        oiiotool "$f" --compression piz -o "$OUT/o-piz.exr" && oiiotool "$f" --compression none -o "$OUT/o-none.exr"
        z=$((z + $(bytes "$f"))) p=$((p + $(bytes "$OUT/o-piz.exr"))) n=$((n + $(bytes "$OUT/o-none.exr")))
        x=$((x + $(xz -9e -c "$OUT/o-none.exr" | wc -c))) k=$((k + 1))
    done
    printf '  %s objects: ZIP-9 (as stored) %s, PIZ %s, none %s, xz -9e of none %s\n' "$k" "$(mb "$z")" "$(mb "$p")" \
        "$(mb "$n")" "$(mb "$x")"
    printf '  against ZIP-9: PIZ %sx, none %sx, xz -9e %sx\n' "$(ratio "$p" "$z")" "$(ratio "$n" "$z")" "$(ratio "$x" "$z")"
fi
