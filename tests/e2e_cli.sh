#!/usr/bin/env bash
# The CLI contract: --help everywhere, one-line errors naming the file for bad input, exit
# codes a CI script can trust, and no run that looks complete after a failure (disk full).
# usage: e2e_cli.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
SEQ=$SRC/scenes/cornell-box/cornell-box-ci.json
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"

for c in record replay bless check info export golden merge lineage tracebench; do
  "$ISPM" $c --help > "$WORK/help.txt" || fail "$c --help exited $?"
  grep -q "usage: ispm $c" "$WORK/help.txt" || fail "$c --help prints no usage"
done
"$ISPM" --help > /dev/null || fail "--help"
# --version (and every manifest's tool.git) names the commit the binary was built from, read at
# build time (cmake/git_rev.cmake), "-dirty" when tracked files differed from it
if command -v git > /dev/null && rev=$(git -C "$SRC" rev-parse --short=12 HEAD 2> /dev/null); then
  "$ISPM" --version | grep -Eq "^ispm [0-9.]+ \($rev(-dirty)?\)$" || fail "--version does not name HEAD $rev: $("$ISPM" --version)"
fi
"$ISPM" frobnicate > /dev/null 2>&1; [ $? -eq 2 ] || fail "unknown command must exit 2"
"$ISPM" record "$SEQ" > /dev/null 2>&1; [ $? -eq 2 ] || fail "record without -o must exit 2"

# expect_input_error FILE [NAMED]: record exits 2 with exactly one line on stderr naming the
# file at fault (NAMED, default FILE itself).
expect_input_error() {
  "$ISPM" record "$1" -o "$WORK/bad" --quiet 2> "$WORK/err.txt"; rc=$?
  [ $rc -eq 2 ] || fail "record $1: exit $rc, want 2"
  [ "$(wc -l < "$WORK/err.txt")" -eq 1 ] || { cat "$WORK/err.txt"; fail "record $1: want one error line"; }
  named=${2:-$(basename "$1")}
  grep -qF "$named" "$WORK/err.txt" || { cat "$WORK/err.txt"; fail "error does not name $named"; }
  [ ! -f "$WORK/bad/manifest.json" ] || fail "a manifest was written for bad input"
}
expect_input_error "$WORK/missing.json"
printf '{"scene": "x.gltf", "frames": 2,' > "$WORK/truncated.json"; expect_input_error "$WORK/truncated.json"
sed 's/"frames": *[0-9]*/"frames": -3/' "$SEQ" > "$WORK/negative.json"; expect_input_error "$WORK/negative.json"
printf '{"scene": "nowhere.gltf", "frames": 1, "fps": 8, "resolution": [8, 8], "camera": {"node": "Camera"}}' \
  > "$WORK/noscene.json"; expect_input_error "$WORK/noscene.json" nowhere.gltf
mkdir -p "$WORK/s"; printf '{"asset": {"version": "2.0"}, "nodes": [{"mesh": 7}]}' > "$WORK/s/bad.gltf"
printf '{"scene": "bad.gltf", "frames": 1, "fps": 8, "resolution": [8, 8], "camera": {"node": "Camera"}}' \
  > "$WORK/s/badscene.json"; expect_input_error "$WORK/s/badscene.json" bad.gltf

# Disk full (a file-size limit): record fails with exit 1, says so, and leaves no manifest.
( ulimit -f 200; "$ISPM" record "$SEQ" -o "$WORK/full" --quiet ) 2> "$WORK/full.err"; rc=$?
[ $rc -eq 1 ] || { cat "$WORK/full.err"; fail "disk full: exit $rc, want 1"; }
[ ! -f "$WORK/full/manifest.json" ] || fail "disk full: a manifest was written"
"$ISPM" replay "$WORK/full" > /dev/null 2>&1; [ $? -eq 4 ] || fail "replay accepted an incomplete run"

# An existing run is not overwritten without --force.
"$ISPM" record "$SEQ" -o "$WORK/run" --quiet --lineage || fail "record"
"$ISPM" record "$SEQ" -o "$WORK/run" --quiet 2> /dev/null; [ $? -ne 0 ] || fail "overwrote a run without --force"
# bless refuses an incomplete run and accepts a complete one.
"$ISPM" bless "$WORK/full" "$WORK/g1" > /dev/null 2>&1; [ $? -eq 2 ] || fail "bless accepted an incomplete run"
"$ISPM" bless "$WORK/run" "$WORK/g2" > /dev/null || fail "bless"
"$ISPM" replay "$WORK/run" --golden "$WORK/g2" > /dev/null || fail "replay against a fresh bless"
# record writes by-kind by default (ZIP level 1 for the kinds it shrinks cheaply); the golden bless makes of it is zip (test_replay checks the bits).
grep -q '"compression":[[:space:]]*"by-kind"' "$WORK/run/manifest.json" || fail "record: default compression not by-kind"
grep -q '"compression":[[:space:]]*"zip"' "$WORK/g2/manifest.json" || fail "bless: golden not recompressed to zip"
# Issue 22: capture_compression changes the frame files' bytes, never a buffer's bits; --capture
# records only the buffers it names, with the same bits. A small variant of the CI sequence.
small() { # NAME SETTINGS: a 2-frame 32x32 copy of the CI sequence with extra settings
  sed -e 's#"scene": *"cornell-box.gltf"#"scene": "'"$SRC"'/scenes/cornell-box/cornell-box.gltf"#' \
      -e 's#"frames": *8#"frames": 2#' -e 's#"resolution": *\[160, *160\]#"resolution": [32, 32]#' \
      -e 's#"settings": *{#"settings": {'"$2"'#' "$SEQ" > "$WORK/$1.json"
}
small zip '"capture_compression": "zip", '
small rle '"capture_compression": "rle", '
small dflt ''
small lossy '"capture_compression": "b44", '
"$ISPM" record "$WORK/zip.json" -o "$WORK/zip" --quiet || fail "record zip"
"$ISPM" record "$WORK/rle.json" -o "$WORK/rle" --quiet || fail "record rle"
expect_input_error "$WORK/lossy.json"
digests() { sed -n '/"frames":/,$p' "$1/manifest.json" | grep -E '"(name|digest)"'; } # the buffers' only
[ "$(digests "$WORK/zip" | grep -c digest)" -gt 20 ] || fail "zip: too few buffers"
diff <(digests "$WORK/zip") <(digests "$WORK/rle") > /dev/null || fail "rle and zip: digests differ"
grep -q '"compression":[[:space:]]*"rle"' "$WORK/rle/manifest.json" || fail "rle: not in the manifest"
cmp -s "$WORK/zip/frames/000000.exr" "$WORK/rle/frames/000000.exr" && fail "rle: same bytes as zip"
"$ISPM" replay "$WORK/rle" --quiet > /dev/null || fail "replay of the rle run"
"$ISPM" record "$WORK/dflt.json" -o "$WORK/display" --quiet --capture 'final.*,nothing' || fail "record --capture"
[ "$(digests "$WORK/display" | grep -c digest)" -eq 2 ] || fail "--capture final.*: want 2 buffers"
display() { digests "$1" | grep -A1 '"final.display"' | grep digest; }
[ "$(display "$WORK/zip" | wc -l)" -eq 2 ] || fail "zip: want 2 final.display digests"
diff <(display "$WORK/zip") <(display "$WORK/display") > /dev/null ||
  fail "--capture: final.display differs from the full run's"
"$ISPM" record "$WORK/zip.json" -o "$WORK/bad" --capture 'a,,b' 2> /dev/null; [ $? -eq 2 ] || fail "--capture a,,b must exit 2"
# Issue 13: "bounce_strata" changes the bounce maps and the photons (not the direct light), is
# recorded in the manifest, replays bit-exact; a size that is not a power of two is bad input.
small strata '"bounce_strata": 8, '
small strata3 '"bounce_strata": 3, '
"$ISPM" record "$WORK/strata.json" -o "$WORK/strata" --quiet || fail "record bounce_strata 8"
expect_input_error "$WORK/strata3.json"
grep -qE '"bounce_strata":[[:space:]]*8' "$WORK/strata/manifest.json" || fail "bounce_strata: not in the manifest"
grep -q '"bounce_strata"' "$WORK/zip/manifest.json" && fail "bounce_strata recorded without being set"
same_as_zip() { diff <(digests "$WORK/zip" | grep -A1 "\"$1\"") <(digests "$WORK/strata" | grep -A1 "\"$1\"") > /dev/null; }
same_as_zip direct.radiance || fail "bounce_strata changed the direct light"
same_as_zip photons.map && fail "bounce_strata left the photon map as it was"
"$ISPM" replay "$WORK/strata" --quiet > /dev/null || fail "replay of the bounce_strata run"
# Frame shards (issue 20; e2e_slurm.sh runs them through Slurm): bad ranges are bad arguments;
# two shards of the run above (both with --lineage, as it was) merge into a run bit-exact against it.
for a in "--frames 3-1" "--frames 2-8" "--frames x" "--shard 2/2" "--shard 1/9" "--warmup 1" "--frames 1-2 --warmup -1"; do
  "$ISPM" record "$SEQ" -o "$WORK/bad-shard" $a --quiet 2> "$WORK/shard.err"; rc=$?
  [ $rc -eq 2 ] && [ "$(wc -l < "$WORK/shard.err")" -eq 1 ] || { cat "$WORK/shard.err"; fail "record $a: exit $rc, want 2 and one line"; }
done
"$ISPM" merge -o "$WORK/m" > /dev/null 2>&1; [ $? -eq 2 ] || fail "merge without shards must exit 2"
"$ISPM" record "$SEQ" -o "$WORK/shard-0" --frames 0-3 --lineage --quiet || fail "record --frames 0-3"
"$ISPM" record "$SEQ" -o "$WORK/shard-1" --shard 1/2 --warmup 2 --overlap 2 --lineage --quiet || fail "record --shard 1/2"
grep -q '"warmup":[[:space:]]*2' "$WORK/shard-1/manifest.json" || fail "the shard's manifest lacks its warm-up"
"$ISPM" merge "$WORK/shard-1" -o "$WORK/merged" 2> "$WORK/merge.err"; [ $? -eq 2 ] || fail "merge of a gap must exit 2"
grep -q "frames 0-3 are in no shard" "$WORK/merge.err" || { cat "$WORK/merge.err"; fail "merge: no gap named"; }
[ ! -e "$WORK/merged/manifest.json" ] || fail "a refused merge left a manifest"
"$ISPM" merge "$WORK/shard-1" "$WORK/shard-0" -o "$WORK/merged" > /dev/null || fail "merge"
"$ISPM" replay "$WORK/merged" --golden "$WORK/run" > "$WORK/merged.out" || { cat "$WORK/merged.out"; fail "replay of the merged run"; }
grep -qE "0 failed, 0 warned, 0 within tolerance, ([0-9]+) bit-exact \(\1 buffers, 8 frames\)" "$WORK/merged.out" ||
  { cat "$WORK/merged.out"; fail "merged run not bit-exact against the one-machine run"; }
# The manifests differ only in timings, the command line and the shards' provenance.
stable() { grep -vE '"(ms|command)":' "$1/manifest.json" | awk '/^\t"shards":/ { skip = 1 } /^\t"frames":/ { skip = 0 } !skip'; }
diff <(stable "$WORK/run") <(stable "$WORK/merged") > "$WORK/merged.diff" || { head -20 "$WORK/merged.diff"; fail "merged manifest differs"; }

# Pixel lineage (issue 19) on the CI run recorded with --lineage: at a lit floor pixel, a wall in
# the shadowed corner and the box, the listed photons' contributions add up to splat.indirect
# (1e-5 relative: the GPU's blending order differs from the listing's) and their number is
# splat.count; the shadow verdict agrees with direct.radiance (one light: 0 exactly when the
# PCF visibility is 0) and with the stored depth; the surface point is followed through frames.
for px in 10,150 40,100 80,140 120,60; do
  "$ISPM" lineage "$WORK/run" --frame 1 --pixel $px --json --chain 1 > "$WORK/lineage.json" || fail "lineage $px exited $?"
  python3 - "$WORK/lineage.json" "$px" <<'PY' || fail "lineage $px"
import json, sys
j = json.load(open(sys.argv[1])); px = sys.argv[2]
def check(c, what):
    if not c:
        sys.exit("pixel %s: %s" % (px, what))
check(j["covered"] and j["check"]["ok"] and j["check"]["count_equal"], "check not ok: %s" % j.get("check"))
ph = j["photons"]
check(0 < len(ph) < j["photons_in_map"] and len(ph) == j["splat_count"], "photon count")
for c in range(3):
    s = sum(p["contribution"][c] for p in ph)
    check(abs(s - j["splat"][c]) <= 1e-5 * abs(j["splat"][c]), "channel %d: sum %r, splat %r" % (c, s, j["splat"][c]))
for p in ph:
    check(p["bounce"] >= 2 and p["light"] == 0 and 0 <= p["face"] < 6 and p["radius"] > 0, "photon origin %r" % p)
l = j["lights"][0]
direct = next(b for b in j["buffers"] if b["name"] == "direct.radiance")["values"]["R"]
lit = l["verdict"] == "lit"
check(lit == (l["compared"] <= l["stored"] + l["tolerance"]), "verdict against depths %r" % l)
if l["visibility"] in (0, 1):
    check(lit == (direct > 0), "verdict %s but direct.radiance %r" % (l["verdict"], direct))
if px == "10,150":
    check(lit and l["stored"] > l["distance"], "the lit floor pixel's shadow texel is not lit: %r" % l)
chain = j["motion_chain"]
check(len(chain) >= 2 and any(s["frame"] == 1 and s["pixel"] == [int(v) for v in px.split(",")] for s in chain), "chain")
PY
done
"$ISPM" lineage "$WORK/run" --frame 1 --pixel 10,150 > "$WORK/lineage.txt" || fail "lineage (text) exited $?"
[ "$(grep -c '^  frame [0-9]* pixel' "$WORK/lineage.txt")" -ge 4 ] || fail "lineage: the floor point is not followed through the frames"
"$ISPM" lineage "$WORK/run" --frame 9 --pixel 10,150 > /dev/null 2>&1; [ $? -eq 2 ] || fail "lineage: frame 9 must exit 2"
"$ISPM" lineage "$WORK/run" --frame 1 --pixel 160,0 > /dev/null 2>&1; [ $? -eq 2 ] || fail "lineage: pixel outside must exit 2"
# tracebench (issue 22 item 4): measures, checks the trace's map against the ray-by-ray trace
# and rtcIntersect4 against rtcIntersect1; bad arguments exit 2.
"$ISPM" tracebench "$SEQ" --repeats 1 --photons 2048 > "$WORK/tb.txt" || { cat "$WORK/tb.txt"; fail "tracebench"; }
grep -q "Mrays/s" "$WORK/tb.txt" && grep -q "ratio" "$WORK/tb.txt" || fail "tracebench prints no rates"
grep -q "ray-by-ray trace: yes" "$WORK/tb.txt" || { cat "$WORK/tb.txt"; fail "tracebench: the map differs"; }
grep -q "bit-identical to rtcIntersect1" "$WORK/tb.txt" || { cat "$WORK/tb.txt"; fail "tracebench: packets differ"; }
"$ISPM" tracebench "$SEQ" --repeats 0 > /dev/null 2>&1; [ $? -eq 2 ] || fail "tracebench --repeats 0 must exit 2"
"$ISPM" tracebench "$WORK/missing.json" > /dev/null 2>&1; [ $? -eq 2 ] || fail "tracebench of a missing sequence must exit 2"
echo "e2e_cli: ok"
