#!/usr/bin/env bash
# The daily regression suite end to end, on recordings of the CI sequence (cornell-box-ci,
# 160x160, 8 frames; the colour buffers and the eye G-buffer that stability needs captured): kernel_radius variants (0.14, 0.16) that differ
# slightly everywhere, a dim spot light added on the back wall that differs locally, and a
# changed material on the short box.
#   - tolerances suggest: from the two kernel_radius runs, with a note per limit; both pass under
#     it; refusals (a NaN run, a margin under 1, an unreadable run) are one line;
#   - block gates: under the suggested file the spot light's final.display stays under
#     failpercent, hardfail, RMSE and FLIP and fails on its worst 8x8 block alone, named in
#     report.txt, report.json, report.junit.xml and outlined in report.html; without the block
#     keys it passes;
#   - expectations: the spot light's failure expected (JUnit skipped), a kernel_radius run under
#     the same rule an unexpected pass, an expired rule, a renderer that does not match, and bad
#     files (unknown key, bad date, a glob naming nothing) as one line and exit 4;
#   - trend: the four runs in order, and by commit in a small repository;
#   - a blessing keeps the golden's expectations.json.
# usage: e2e_gates.sh ISPM SOURCE_DIR WORK_DIR   (run by CTest)
set -u
ISPM=$1; SRC=$2; WORK=$3
MUTATE=$(dirname "$ISPM")/../tests/ispm_test_mutate
fail() { echo "FAIL: $*"; exit 1; }
command -v python3 >/dev/null || { echo "python3 not found: skipped"; exit 77; }
rm -rf "$WORK"; mkdir -p "$WORK/s"
cp "$SRC/scenes/cornell-box/cornell-box.gltf" "$WORK/s/"

# The variants: the CI sequence's settings and frames, eight buffers captured.
python3 - "$WORK/s" "$SRC/scenes/cornell-box/cornell-box-ci.json" <<'PY' || fail "variants"
import json, sys
d, ci = sys.argv[1], json.load(open(sys.argv[2]))
g = json.load(open(d + "/cornell-box.gltf"))
spot = json.loads(json.dumps(g))   # a dim spot light aimed at the back wall
spot["extensions"]["KHR_lights_punctual"]["lights"].append(
    {"name": "spot", "type": "spot", "color": [1, 1, 1], "intensity": 1.0,
     "spot": {"innerConeAngle": 0.0, "outerConeAngle": 0.09}})
spot["nodes"].append({"name": "Spot", "translation": [0.45, 1.45, 0.2],
                      "extensions": {"KHR_lights_punctual": {"light": 1}}})
spot["scenes"][0]["nodes"].append(len(spot["nodes"]) - 1)
json.dump(spot, open(d + "/spot.gltf", "w"))
mat = json.loads(json.dumps(g))    # the short box turned orange
box = [m for m in mat["materials"] if m["name"] == "shortBox"][0]
box["pbrMetallicRoughness"]["baseColorFactor"] = [0.725, 0.6, 0.45, 1.0]
json.dump(mat, open(d + "/material.gltf", "w"))
for name, scene, kr in [("base", "cornell-box.gltf", None), ("kr014", "cornell-box.gltf", 0.14),
                        ("kr016", "cornell-box.gltf", 0.16), ("spot", "spot.gltf", None),
                        ("material", "material.gltf", None)]:
    s = json.loads(json.dumps(ci))
    s["scene"] = scene
    if kr is not None:
        s["settings"]["kernel_radius"] = kr
    s["settings"]["threads"] = 2
    s["capture"] = ["final.display", "composite.radiance", "direct.radiance", "indirect.radiance",
                    "gbuffer.position", "gbuffer.normal", "gbuffer.material", "gbuffer.motion"]
    json.dump(s, open("%s/%s.json" % (d, name), "w"))
PY
for v in base kr014 kr016 spot material; do
  "$ISPM" record "$WORK/s/$v.json" -o "$WORK/$v" --quiet > /dev/null || fail "record $v"
done
G=$WORK/golden
"$ISPM" bless "$WORK/base" "$G" > /dev/null || fail "bless"
# What a failing pixel is (|delta| > 0.02 in display units); the limits come from evidence.
echo '{"default": {"warn": 1e-6, "warnrelative": 1e-6, "fail": 0.02, "failrelative": 0, "failpercent": 0, "hardfail": 1}}' \
  > "$G/tolerances.json"
one_line() { # one_line FILE WHAT: stderr held exactly one line
  [ "$(wc -l < "$1")" -eq 1 ] || { cat "$1"; fail "$2: want one line on stderr"; }
}

# --- tolerances suggest
SUG=$WORK/suggested.json
"$ISPM" tolerances suggest "$WORK/kr014" "$WORK/kr016" --golden "$G" -o "$SUG" --margin 1.25 > "$WORK/suggest.out" \
  || fail "tolerances suggest exited $?"
cat "$WORK/suggest.out"
python3 - "$SUG" "$WORK" <<'PY' || fail "suggested file"
import json, sys
t = json.load(open(sys.argv[1]))
rules = {r["match"]: r for r in t["buffers"]}
assert rules["direct.radiance"] == {"match": "direct.radiance", "exact": True, "note": "bit-exact in every run"}, rules["direct.radiance"]
fd = rules["final.display"]
for k in ("hardfail", "failpercent", "rmse_fail", "block_fail", "block_failrelative", "flip_mean_fail", "flip_p99_fail"):
    assert fd[k] > 0, k
    assert sys.argv[2] + "/kr01" in fd["note"][k] and "frame" in fd["note"][k], fd["note"][k]
assert fd["fail"] == 0.02 and fd["failrelative"] == 0, fd
print("suggested final.display: " + ", ".join("%s %g" % (k, fd[k]) for k in
      ("hardfail", "failpercent", "rmse_fail", "block_fail", "flip_mean_fail", "flip_p99_fail")))
PY
cp "$SUG" "$G/tolerances.json"
for v in kr014 kr016; do
  "$ISPM" replay "$WORK/$v" --golden "$G" -q > "$WORK/$v.out"; rc=$?
  [ $rc -eq 1 ] || { cat "$WORK/$v.out"; fail "$v under the suggested tolerances exited $rc, want 1 (settings differ)"; }
  grep -q "0 failed, 0 warned" "$WORK/$v.out" || { cat "$WORK/$v.out"; fail "$v does not pass under the suggested file"; }
done
# refusals
cp -r "$WORK/kr014" "$WORK/nan"
"$MUTATE" "$WORK/nan" 2 final.display 10 10 R set nan || fail "mutate"
"$ISPM" tolerances suggest "$WORK/kr016" "$WORK/nan" --golden "$G" -o "$WORK/x.json" > /dev/null 2> "$WORK/err"; rc=$?
[ $rc -eq 1 ] || fail "suggest with a NaN run exited $rc, want 1"
one_line "$WORK/err" "suggest NaN"; grep -q "$WORK/nan: frame 2 final.display" "$WORK/err" || fail "NaN refusal does not name the run"
[ ! -e "$WORK/x.json" ] || fail "a refused suggestion wrote its file"
"$ISPM" tolerances suggest "$WORK/kr016" --golden "$G" -o "$WORK/x.json" --margin 0.5 > /dev/null 2> "$WORK/err"; rc=$?
[ $rc -eq 2 ] || fail "--margin 0.5 exited $rc, want 2"
"$ISPM" tolerances suggest "$WORK/nothere" --golden "$G" -o "$WORK/x.json" > /dev/null 2> "$WORK/err"; rc=$?
[ $rc -eq 4 ] || fail "suggest with a missing run exited $rc, want 4"
one_line "$WORK/err" "suggest missing run"

# --- block gates: the spot light, final.display
"$ISPM" replay "$WORK/spot" --golden "$G" --buffers final.display --report "$WORK/spot-rep" > "$WORK/spot.out"; rc=$?
cat "$WORK/spot.out"
[ $rc -eq 2 ] || fail "spot light: replay exited $rc, want 2"
grep -q "worst 8×8 block: frame [0-9] final.display" "$WORK/spot.out" || fail "report.txt does not name the worst block"
grep -q "block over block_fail" "$WORK/spot.out" || fail "report.txt does not say the block gate failed"
python3 - "$WORK/spot-rep/report.json" "$G/tolerances.json" <<'PY' || fail "spot light: report.json"
import json, sys
r, t = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
lim = [b for b in t["buffers"] if b["match"] == "final.display"][0]
w = r["worst_block"]
assert w["buffer"] == "final.display" and w["size"] == 8 and w["value"] > lim["block_fail"], w
print("| frame | failing px %% (limit %g) | max |d| (hardfail %g) | RMSE (%g) | FLIP mean / p99 (%g / %g) | worst 8x8 block (block_fail %g) |"
      % (lim["failpercent"], lim["hardfail"], lim["rmse_fail"], lim["flip_mean_fail"], lim["flip_p99_fail"], lim["block_fail"]))
for f in r["frames"]:
    b = f["buffers"][0]; m = b["metrics"]; bl = m["block"]["abs"]
    assert m["fail_reasons"] == ["block"], m["fail_reasons"]
    assert m["fail_percent"] <= lim["failpercent"] and m["max_abs_error"] <= lim["hardfail"] and m["rmse"] <= lim["rmse_fail"]
    assert b["flip"]["mean"] <= lim["flip_mean_fail"] and b["flip"]["p99"] <= lim["flip_p99_fail"]
    print("| %d | %.3f | %.4f | %.5f | %.4f / %.4f | %.4f at (%d,%d) |" % (f["index"], m["fail_percent"], m["max_abs_error"],
          m["rmse"], b["flip"]["mean"], b["flip"]["p99"], bl["value"], bl["x"], bl["y"]))
PY
grep -q '<property name="worst_block" value="worst 8×8 block: frame' "$WORK/spot-rep/report.junit.xml" \
  || fail "JUnit has no worst_block property"
grep -q 'class="blk"' "$WORK/spot-rep/report.html" || fail "report.html outlines no block"
grep -q 'id="worst-block"' "$WORK/spot-rep/report.html" || fail "report.html does not name the worst block"
# without the block keys, failpercent and the rest let the spot light through
python3 - "$G/tolerances.json" "$WORK/noblock.json" <<'PY' || fail "noblock"
import json, sys
t = json.load(open(sys.argv[1]))
for b in t["buffers"]:
    b.pop("block_fail", None); b.pop("block_failrelative", None)
json.dump(t, open(sys.argv[2], "w"))
PY
"$ISPM" replay "$WORK/spot" --golden "$G" -t "$WORK/noblock.json" --buffers final.display --report "$WORK/spot-nb" -q \
  > "$WORK/spot-nb.out"; rc=$?
[ $rc -eq 1 ] || { cat "$WORK/spot-nb.out"; fail "spot light without block gates exited $rc, want 1 (provenance only)"; }
grep -q "0 failed, 0 warned, 8 within tolerance" "$WORK/spot-nb.out" || fail "spot light without block gates: not within"
# the changed material fails on every gate
"$ISPM" replay "$WORK/material" --golden "$G" --buffers final.display --report "$WORK/mat-rep" -q > /dev/null; rc=$?
[ $rc -eq 2 ] || fail "material: replay exited $rc, want 2"
python3 - "$WORK/mat-rep/report.json" <<'PY' || fail "material: report.json"
import json, sys
for f in json.load(open(sys.argv[1]))["frames"]:
    why = f["buffers"][0]["metrics"]["fail_reasons"]
    assert "percent" in why and "block" in why and "flip" in why, why
PY

# --- expectations
E=$G/expectations.json
echo '[{"match": "final.display", "expect": "fail", "reason": "spot light on the back wall, under review",
        "until": "2099-12-31", "renderer": "llvmpipe*"}]' > "$E"
"$ISPM" replay "$WORK/spot" --golden "$G" --buffers final.display --report "$WORK/x1" > "$WORK/x1.out"; rc=$?
[ $rc -eq 1 ] || { cat "$WORK/x1.out"; fail "expected failures: exit $rc, want 1 (provenance warns)"; }
grep -q "8 expected failures, 0 failed" "$WORK/x1.out" || { cat "$WORK/x1.out"; fail "text: expected failures"; }
grep -q "^XFAIL.*expected failure: spot light on the back wall" "$WORK/x1.out" || fail "text: XFAIL line with its reason"
grep -q 'skipped="8"' "$WORK/x1/report.junit.xml" || fail "JUnit: 8 skipped"
grep -q '<skipped message="expected failure: spot light on the back wall, under review"/>' "$WORK/x1/report.junit.xml" \
  || fail "JUnit: skipped with the reason"
grep -q 'expected failure: spot light' "$WORK/x1/report.html" || fail "HTML: the reason"
grep -q 'id="expectations"' "$WORK/x1/report.html" || fail "HTML: expectations section"
python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); assert r["counts"]["expected failure"] == 8 and r["counts"]["fail"] == 0; assert r["frames"][0]["buffers"][0]["expected_failure"]["reason"].startswith("spot")' \
  "$WORK/x1/report.json" || fail "JSON: expected failures"
# a run where the buffer passes: an unexpected pass, a warning
"$ISPM" replay "$WORK/kr014" --golden "$G" --buffers final.display --report "$WORK/x2" -q > "$WORK/x2.out"; rc=$?
[ $rc -eq 1 ] || fail "unexpected pass: exit $rc, want 1"
grep -q "UNEXPECTED PASS final.display" "$WORK/x2.out" || { cat "$WORK/x2.out"; fail "text: unexpected pass"; }
grep -q 'name="unexpected pass: final.display"' "$WORK/x2/report.junit.xml" || fail "JUnit: unexpected pass"
grep -q 'unexpected pass' "$WORK/x2/report.html" || fail "HTML: unexpected pass"
python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); assert r["expectations"]["unexpected_passes"][0]["buffer"] == "final.display"' \
  "$WORK/x2/report.json" || fail "JSON: unexpected pass"
"$ISPM" replay "$WORK/kr014" --golden "$G" --buffers final.display --report "$WORK/x2" -q --expectations /dev/null \
  > /dev/null 2>&1; rc=$?
[ $rc -eq 4 ] || fail "an empty expectations file exited $rc, want 4"
# an expired rule excuses nothing
"$ISPM" replay "$WORK/spot" --golden "$G" --buffers final.display --report "$WORK/x3" -q --today 2100-01-01 > "$WORK/x3.out"; rc=$?
[ $rc -eq 2 ] || fail "expired rule: exit $rc, want 2"
grep -q "EXPIRED rules\[0\]" "$WORK/x3.out" || fail "text: expired rule"
grep -q 'name="expired: rules\[0\] final.display"' "$WORK/x3/report.junit.xml" || fail "JUnit: expired rule"
# a rule for another renderer does not apply
sed 's/llvmpipe\*/NVIDIA*/' "$E" > "$WORK/nv.json"
"$ISPM" replay "$WORK/spot" --golden "$G" --buffers final.display --report "$WORK/x4" -q --expectations "$WORK/nv.json" \
  > /dev/null; rc=$?
[ $rc -eq 2 ] || fail "a rule for another renderer: exit $rc, want 2"
# bad files: one line naming the file, exit 4
for bad in '[{"match": "final.display", "expect": "fail", "reason": "r", "owner": "me"}]' \
           '[{"match": "final.display", "expect": "fail", "reason": "r", "until": "2026-02-30"}]' \
           '[{"match": "final.dsplay", "expect": "fail", "reason": "r"}]' \
           '[{"match": "final.display", "expect": "fail"}]'; do
  echo "$bad" > "$WORK/bad.json"
  "$ISPM" replay "$WORK/spot" --golden "$G" --expectations "$WORK/bad.json" --report "$WORK/x5" -q > /dev/null 2> "$WORK/err"; rc=$?
  [ $rc -eq 4 ] || fail "bad expectations ($bad): exit $rc, want 4"
  one_line "$WORK/err" "bad expectations"
  grep -q "$WORK/bad.json: rules\[0\]" "$WORK/err" || { cat "$WORK/err"; fail "the error does not name the file and rule"; }
done
"$ISPM" replay "$WORK/spot" --golden "$G" --today 2026-13-01 > /dev/null 2>&1; rc=$?
[ $rc -eq 2 ] || fail "--today 2026-13-01 exited $rc, want 2"
rm "$E"

# --- trend: every run replayed (RUN/replay), in the order given
for v in kr014 kr016 spot material; do
  "$ISPM" replay "$WORK/$v" --golden "$G" -q > /dev/null
done
"$ISPM" trend "$WORK/kr014" "$WORK/kr016" "$WORK/spot" "$WORK/material" -o "$WORK/trend" > "$WORK/trend.out" \
  || fail "trend exited $?"
cat "$WORK/trend.out"
[ -s "$WORK/trend/img/trend-flip_mean.png" ] || fail "no FLIP mean chart"
grep -q 'img/trend-flip_mean.png' "$WORK/trend/trend.html" || fail "trend.html does not show the chart"
python3 - "$WORK/trend/trend.json" <<'PY' || fail "trend.json"
import json, sys
t = json.load(open(sys.argv[1]))
assert [r["verdict"] for r in t["runs"]] == ["WARN", "WARN", "FAIL", "FAIL"], [r["verdict"] for r in t["runs"]]
s = [x for x in t["series"] if x["metric"] == "flip_mean" and x["name"] == "final.display"][0]
assert s["moved_most"]["to"] == 3, s                  # into the material change
print("FLIP mean of final.display over the runs: " + ", ".join("%.4f" % v for v in s["values"]))
assert any(x["metric"] == "pass_share" for x in t["series"]) and t["runs"][0]["frame_ms"] > 0
assert t["runs"][0]["buffers"]["final.display"]["flicker_reprojected"] is not None
PY
# --by-commit: runs of two commits of a small repository, given newest first
R=$WORK/repo
git init -q "$R" && git -C "$R" -c user.name=t -c user.email=t@t commit -q --allow-empty -m one \
  && git -C "$R" -c user.name=t -c user.email=t@t commit -q --allow-empty -m two || fail "git repository"
one=$(git -C "$R" rev-parse --short=12 HEAD~1); two=$(git -C "$R" rev-parse --short=12 HEAD)
for pair in "old:$one:kr014" "new:$two-dirty:material"; do
  IFS=: read -r name rev from <<< "$pair"
  mkdir -p "$WORK/c/$name/replay"
  cp "$WORK/$from/replay/report.json" "$WORK/c/$name/replay/"
  python3 -c 'import json,sys; m=json.load(open(sys.argv[1])); m["tool"]["git"]=sys.argv[3]; json.dump(m, open(sys.argv[2], "w"))' \
    "$WORK/$from/manifest.json" "$WORK/c/$name/manifest.json" "$rev" || fail "manifest copy"
done
"$ISPM" trend "$WORK/c/new" "$WORK/c/old" -o "$WORK/trend2" --by-commit --repo "$R" > /dev/null || fail "trend --by-commit exited $?"
python3 -c 'import json,sys; t=json.load(open(sys.argv[1])); assert [r["run"].split("/")[-1] for r in t["runs"]] == ["old", "new"], t["runs"]' \
  "$WORK/trend2/trend.json" || fail "--by-commit did not order the runs by commit"
python3 -c 'import json,sys; m=json.load(open(sys.argv[1])); m["tool"]["git"]="0123456789ab"; json.dump(m, open(sys.argv[1], "w"))' \
  "$WORK/c/old/manifest.json"
"$ISPM" trend "$WORK/c/new" "$WORK/c/old" -o "$WORK/trend3" --by-commit --repo "$R" > /dev/null 2> "$WORK/err"; rc=$?
[ $rc -eq 2 ] || fail "trend with an unknown commit exited $rc, want 2"
one_line "$WORK/err" "unknown commit"
"$ISPM" trend "$WORK/base" -o "$WORK/trend4" > /dev/null 2> "$WORK/err"; rc=$?
[ $rc -eq 4 ] || fail "trend of a run never replayed exited $rc, want 4"
one_line "$WORK/err" "not replayed"
# a blessing keeps the golden's expectations, as it keeps its tolerances
echo '[{"match": "final.display", "expect": "fail", "reason": "kept"}]' > "$E"
"$ISPM" bless "$WORK/spot" "$G" --accept > /dev/null || fail "bless --accept exited $?"
grep -q '"reason": "kept"' "$E" || fail "bless dropped expectations.json"
echo "e2e_gates: OK"
