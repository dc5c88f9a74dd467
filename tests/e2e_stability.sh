#!/usr/bin/env bash
# End-to-end temporal stability (docs/stability.md): record every stress sequence
# (scenes/stress/*.json), replay it against golden/stress-<name> (bit-exact and the stability
# verdicts must pass), then show what must hold and what must fail:
#   - random maps, a small cube moving on the far side of a wall: the other half's static-pixel
#     flicker of indirect.radiance is exactly 0 in every frame; with per-frame random it is not;
#   - a run that flickers more than its golden (per-frame random against the random-maps golden,
#     pixel differences tolerated) fails on stability alone (exit 2), as does an absolute limit;
#   - a fabricated reference run gives a temporal error, and a limit on it fails;
#   - a malformed "stability" object is refused (exit 4, one line).
# usage: e2e_stability.sh ISPM SOURCE_DIR WORK_DIR   (run by CTest)
set -u
ISPM=$1; SRC=$2; WORK=$3
REFTOOL=$(dirname "$ISPM")/../tests/ispm_test_reference
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"
# A number from a report.json: jnum FILE PYTHON-EXPRESSION-ON-r (r = the parsed report)
jnum() { python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print($2)" "$1"; }

for seq in "$SRC"/scenes/stress/*.json; do
  name=$(basename "$seq" .json)
  "$ISPM" record "$seq" -o "$WORK/$name" --quiet || fail "record $name exited $?"
  "$ISPM" replay "$WORK/$name" --golden "$SRC/golden/stress-$name" --quiet > "$WORK/$name.out"; rc=$?
  cat "$WORK/$name.out"
  [ $rc -eq 0 ] || fail "$name: replay against its golden exited $rc"
  rep=$WORK/$name/replay/report.json
  [ "$(jnum "$rep" "r['counts']['bit-exact'] == r['buffer_count']")" = True ] || fail "$name: not bit-exact"
  [ "$(jnum "$rep" "r['stability']['verdict']")" = OK ] || fail "$name: stability verdict not OK"
  [ -f "$WORK/$name/replay/stability/manifest.json" ] || fail "$name: no stability run"
  [ -f "$WORK/$name/replay/img/stability-reprojected.png" ] || fail "$name: no stability chart"
  grep -q 'img/stability-reprojected.png' "$WORK/$name/replay/report.html" || fail "$name: report.html has no chart"
done

# The stability run is a run: replay reads it (integrity, digests) like any other.
"$ISPM" replay "$WORK/corner/replay/stability" --report "$WORK/stability-of-corner" --quiet > /dev/null; rc=$?
[ $rc -eq 0 ] || fail "the stability run does not replay cleanly ($rc)"
VIEW=$(dirname "$ISPM")/../viewer/ispm-view
if [ -x "$VIEW" ]; then  # built only with SDL2
  "$VIEW" "$WORK/corner/replay/stability" --list | grep -qx stability.indirect.radiance \
    || fail "ispm-view does not list stability.indirect.radiance"
fi

# Random maps: the right half of the divider scene (x >= 56 of 96) never flickers; per-frame does.
region_max() {  # RUN FRAME: max of stability.indirect.radiance over columns 56..95
  oiiotool "$1/replay/stability/frames/$(printf %06d "$2").exr" --subimage stability.indirect.radiance \
    --cut 40x64+56+0 --printstats 2>/dev/null | awk '/Stats Max/ {print $3}'
}
for f in 1 2 3 4 5; do
  m=$(region_max "$WORK/random-maps" $f)
  [ -n "$m" ] || fail "cannot read the stability image of random-maps frame $f"
  awk -v m="$m" 'BEGIN {exit !(m == 0)}' || fail "random maps: frame $f far-region flicker max $m, want exactly 0"
  p=$(region_max "$WORK/random-per-frame" $f)
  awk -v p="$p" 'BEGIN {exit !(p > 0.1)}' || fail "per-frame random: frame $f far-region flicker max $p, want > 0.1"
done
pm=$(jnum "$WORK/random-maps/replay/report.json" "[b for b in r['stability']['buffers'] if b['name']=='indirect.radiance'][0]['static']['mean']")
pf=$(jnum "$WORK/random-per-frame/replay/report.json" "[b for b in r['stability']['buffers'] if b['name']=='indirect.radiance'][0]['static']['mean']")
echo "indirect.radiance static mean: maps $pm, per-frame $pf"
awk -v a="$pm" -v b="$pf" 'BEGIN {exit !(b > 3 * a)}' || fail "per-frame random does not flicker more than maps"

# A change that makes indirect light flicker more than the golden did fails on stability alone:
# the per-frame run against the random-maps golden, every pixel difference tolerated.
cat > "$WORK/loose.json" <<'JSON'
{"default": {"fail": 1e30, "failrelative": 1e30, "hardfail": 1e30, "warn": 1e30, "warnrelative": 1e30},
 "buffers": [{"match": "indirect.radiance", "stability": {"golden_margin": 0}}]}
JSON
"$ISPM" replay "$WORK/random-per-frame" --golden "$SRC/golden/stress-random-maps" --tolerances "$WORK/loose.json" \
  --report "$WORK/worse" > "$WORK/worse.out"; rc=$?
cat "$WORK/worse.out"
[ $rc -eq 2 ] || fail "flicker over the golden's: replay exited $rc, want 2"
grep -q "FAIL  indirect.radiance.*over golden" "$WORK/worse.out" || fail "summary does not name the stability failure"
[ "$(jnum "$WORK/worse/report.json" "r['counts']['fail']")" = 0 ] || fail "pixel comparisons should all pass here"
[ "$(jnum "$WORK/worse/report.json" "r['stability']['verdict']")" = FAIL ] || fail "report.json stability verdict"
grep -q '<failure type="stability"' "$WORK/worse/report.junit.xml" || fail "report.junit.xml has no stability failure"
# ...and so does an absolute limit, on the run's own golden.
cat > "$WORK/abs.json" <<'JSON'
{"buffers": [{"match": "splat.indirect", "stability": {"static_mean": 0.001}}]}
JSON
"$ISPM" replay "$WORK/corner" --golden "$SRC/golden/stress-corner" --tolerances "$WORK/abs.json" --quiet \
  > "$WORK/abs.out"; rc=$?
cat "$WORK/abs.out"
[ $rc -eq 2 ] || fail "absolute static_mean limit: replay exited $rc, want 2"

# Temporal error against a (fabricated) reference: the per-frame run against its own mean.
"$REFTOOL" "$WORK/random-per-frame" "$WORK/ref" || fail "making the reference run"
"$ISPM" replay "$WORK/random-per-frame" --reference "$WORK/ref" --report "$WORK/refrep" --quiet > /dev/null; rc=$?
[ $rc -eq 0 ] || fail "replay with --reference exited $rc"
sd=$(jnum "$WORK/refrep/report.json" "[b for b in r['stability']['buffers'] if b['name']=='indirect.radiance'][0]['temporal_error']['std_mean']")
echo "per-frame random, indirect.radiance temporal std vs reference: $sd"
awk -v s="$sd" 'BEGIN {exit !(s > 0)}' || fail "temporal std against the reference is $sd, want > 0"
cat > "$WORK/tstd.json" <<'JSON'
{"buffers": [{"match": "indirect.radiance", "stability": {"temporal_std_mean": 1e-6}}]}
JSON
"$ISPM" replay "$WORK/random-per-frame" --golden "$SRC/golden/stress-random-per-frame" --reference "$WORK/ref" \
  --tolerances "$WORK/tstd.json" --report "$WORK/tstdrep" --quiet > /dev/null; rc=$?
[ $rc -eq 2 ] || fail "temporal std limit: replay exited $rc, want 2"
# A reference with another frame count is refused (exit 4).
"$ISPM" replay "$WORK/photons-1k" --reference "$WORK/ref" --report "$WORK/badref" > /dev/null 2>&1; rc=$?
[ $rc -eq 4 ] || fail "reference with 6 frames for a 4-frame run: replay exited $rc, want 4"

# Strict parsing: a typo in the stability object is an unreadable tolerance file (exit 4, one line).
echo '{"buffers": [{"match": "x", "stability": {"static_maen": 0}}]}' > "$WORK/typo.json"
"$ISPM" replay "$WORK/corner" --golden "$SRC/golden/stress-corner" --tolerances "$WORK/typo.json" \
  --report "$WORK/typo" > /dev/null 2> "$WORK/typo.err"; rc=$?
[ $rc -eq 4 ] || fail "typo in stability: replay exited $rc, want 4"
[ "$(wc -l < "$WORK/typo.err")" -eq 1 ] && grep -q "static_maen" "$WORK/typo.err" || fail "error is not one line naming the key"

echo "e2e_stability: ok"
