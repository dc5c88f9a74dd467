#!/usr/bin/env bash
# `ispm bench` end to end: a 2 photon counts × 2 methods grid at 32×32 against a stand-in
# reference run (a high-photon ISPM recording renamed by ispm_test_fake_reference: real ones
# come from `ispm reference`). Checks the CSV's shape and values, that ISPM's scatter and the
# k-d gather (the same estimator) have the same errors, the charts and comparison images, and
# that malformed configs fail with one line naming the file, exit 2, and no results.
# usage: e2e_bench.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
FAKE=$(dirname "$ISPM")/../tests/ispm_test_fake_reference
SCENE=$SRC/scenes/cornell-box/cornell-box.gltf
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"
cd "$WORK" || fail "cd $WORK"

"$ISPM" bench --help | grep -q "usage: ispm bench" || fail "bench --help prints no usage"

cat > ref.json <<EOF
{"name": "ref", "scene": "$SCENE", "frames": 2, "fps": 8, "resolution": [32, 32],
 "camera": {"node": "Camera"},
 "settings": {"shadow_map_size": 128, "photon_count": 65536, "kernel_radius": 0.06, "threads": 2},
 "capture": ["indirect.radiance", "composite.radiance"]}
EOF
cat > seq.json <<EOF
{"name": "bench-seq", "scene": "$SCENE", "frames": 2, "fps": 8, "resolution": [32, 32],
 "camera": {"node": "Camera"}, "settings": {"shadow_map_size": 128, "threads": 2}}
EOF
"$ISPM" record ref.json -o refrun --quiet > /dev/null || fail "record of the reference exited $?"
"$FAKE" refrun || fail "fake reference"

cat > bench.json <<EOF
{"sequence": "seq.json", "reference": "refrun", "frames": [1], "repeats": 2, "warmup": 1,
 "grid": {"photon_count": [1024, 4096]},
 "methods": [{"name": "ispm", "settings": {"indirect": "ispm"}},
             {"name": "kd", "settings": {"indirect": "kd-gather"}}]}
EOF
"$ISPM" bench bench.json -o out --quiet > bench.out; rc=$?
[ $rc -eq 0 ] || fail "bench exited $rc"
for f in bench.csv bench.json error_vs_time.png error_vs_time.svg pass_times.png \
         compare_scatter_vs_gather.png compare_scatter_vs_gather.exr; do
  [ -s "out/$f" ] || fail "out/$f missing"
done

# Speed-up against the k-d gather: one stdout line per ispm point, the same ratios in bench.json.
[ "$(grep -c '^speedup vs kd-gather: ispm ' bench.out)" -eq 2 ] || fail "want 2 'speedup vs kd-gather' lines: $(cat bench.out)"
python3 - out/bench.json bench.out <<'PY' || fail "speedup_vs_kd_gather"
import json, re, sys
d = json.load(open(sys.argv[1]))
pts = d["points"]
ups = d["speedup_vs_kd_gather"]
assert len(ups) == 2, ups
lines = [l for l in open(sys.argv[2]) if l.startswith("speedup vs kd-gather: ")]
for u in ups:
    a, b = pts[u["point"]], pts[u["kd_gather_point"]]
    assert a["method"] == "ispm" and b["method"] == "kd"
    assert a["settings"]["photon_count"] == b["settings"]["photon_count"]
    assert abs(u["frame_speedup"] - b["frame_ms"] / a["frame_ms"]) <= 1e-9 * u["frame_speedup"]
    assert abs(u["pass_speedup"] - b["pass_ms"]["gather"] / a["pass_ms"]["splat"]) <= 1e-9 * u["pass_speedup"]
    assert 0 <= u["max_rel"] < 1e-4, u  # the same estimator
    pc = a["settings"]["photon_count"]
    l = [x for x in lines if re.match(r"speedup vs kd-gather: ispm %s " % pc, x)]
    assert len(l) == 1, (pc, lines)
    m = re.search(r"([0-9.]+)x frame .*, ([0-9.]+)x pass", l[0])
    assert m and abs(float(m.group(1)) - u["frame_speedup"]) <= 0.051 and abs(float(m.group(2)) - u["pass_speedup"]) <= 0.051, l[0]
PY

# CSV: header + 4 rows, every row as wide as the header; columns by name.
python3 - out/bench.csv <<'PY' || fail "bench.csv content"
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
hdr = open(sys.argv[1]).readline().strip().split(",")
assert len(rows) == 4, f"{len(rows)} rows"
for col in ["point", "method", "indirect", "photon_count", "frame_ms", "samples", "splat_ms", "gather_ms",
            "photons_ms", "indirect_rmse", "indirect_rel_mse", "indirect_mae", "indirect_max_abs",
            "indirect_block_rmse", "full_rmse", "full_block_rmse", "pareto"]:
    assert col in hdr, f"no column {col}"
for r in rows:
    assert None not in r and all(v != "" for v in r.values()), f"short or empty row {r}"
    assert int(r["samples"]) == 2
    for k in ["frame_ms", "indirect_rmse", "indirect_rel_mse", "indirect_mae", "indirect_max_abs",
              "indirect_block_rmse", "full_rmse", "full_rel_mse", "full_mae", "full_max_abs"]:
        v = float(r[k]); assert math.isfinite(v) and v > 0, f"{k} = {v}"
    for k in hdr:
        if k.endswith("_ms"):
            v = float(r[k]); assert math.isfinite(v) and v >= 0, f"{k} = {v}"
    assert r["pareto"] in ("0", "1")
m = {(r["method"], r["photon_count"]): r for r in rows}
assert set(m) == {("ispm", "1024"), ("ispm", "4096"), ("kd", "1024"), ("kd", "4096")}, set(m)
for pc in ["1024", "4096"]:
    a, b = m[("ispm", pc)], m[("kd", pc)]
    assert a["indirect"] == "ispm" and b["indirect"] == "kd-gather"
    assert float(a["splat_ms"]) > 0 and float(a["gather_ms"]) == 0
    assert float(b["gather_ms"]) > 0 and float(b["splat_ms"]) == 0
    # The same estimator on the same photons: errors agree to float rounding.
    for k in ["indirect_rmse", "indirect_mae", "indirect_block_rmse", "full_rmse"]:
        x, y = float(a[k]), float(b[k])
        assert abs(x - y) <= 1e-4 * max(x, y), f"{k} at {pc} photons: ispm {x}, kd {y}"
# The frame time is the stack of the passes other than the read-back.
for r in rows:
    s = sum(float(r[k]) for k in hdr if k.endswith("_ms") and k not in ("frame_ms", "readback_ms"))
    # medians of parts need not add up to the median of sums exactly; 2 samples of each
    assert s > 0.3 * float(r["frame_ms"]) and s < 3 * float(r["frame_ms"]), f"passes {s} vs frame {r['frame_ms']}"
# at least one point on the Pareto front
assert any(r["pareto"] == "1" for r in rows)
# Bias measures (issue 13): present, in range, the same for scatter and gather.
for r in rows:
    for k in ["indirect_mean_ratio", "indirect_block_p90", "indirect_edge_ratio", "indirect_edge_rel_rmse",
              "indirect_flat_ratio", "indirect_flat_rel_rmse", "indirect_edge_fraction"]:
        v = float(r[k]); assert math.isfinite(v) and v >= 0, f"{k} = {v}"
    assert 0.2 < float(r["indirect_mean_ratio"]) < 5
    assert 0 < float(r["indirect_edge_fraction"]) < 1
for pc in ["1024", "4096"]:
    a, b = m[("ispm", pc)], m[("kd", pc)]
    for k in ["indirect_mean_ratio", "indirect_edge_ratio", "indirect_flat_ratio"]:
        assert abs(float(a[k]) - float(b[k])) <= 1e-4, f"{k} at {pc}: {a[k]} vs {b[k]}"
PY

# Progressive accumulation with a per-frame series against one reference frame.
cat > conv.json <<EOF
{"sequence": "seq.json", "reference": "refrun", "reference_frame": 1, "frames": 2, "report_frames": [0, 1],
 "warmup": 0, "methods": [{"name": "prog", "settings": {"indirect": "kd-gather", "progressive": true,
 "random": "per-frame", "kernel_scaling": "tile-density"}}]}
EOF
"$ISPM" bench conv.json -o conv --quiet > conv.out; rc=$?
[ $rc -eq 0 ] || fail "convergence bench exited $rc"
for f in convergence_frames.png convergence_rmse_frames.png convergence_time.png; do
  [ -s "conv/$f" ] || fail "no conv/$f"
done
python3 - conv/bench.json <<'PY' || fail "convergence bench.json content"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["reference_frame"] == 1
p = j["points"][0]
assert p["settings"]["progressive"] == "true" and p["settings"]["kernel_scaling"] == "tile-density", p["settings"]
s = p["series"]
assert [e["frames_rendered"] for e in s] == [1, 2] and s[1]["elapsed_ms"] > s[0]["elapsed_ms"] > 0
assert all(0 < e["indirect_bias"]["mean_ratio"] < 5 for e in s)
PY

python3 - out/bench.json <<'PY' || fail "bench.json content"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["format"] == "ispm-bench" and len(j["points"]) == 4 and j["frames"] == [1]
assert j["reference_pixel"] == "unknown", j["reference_pixel"]  # a recorded run, not ispm reference
sg = j["scatter_vs_gather"]
assert sg["max_rel"] < 1e-4, sg
PY

# Charts: the sizes plot.h promises, and not blank.
check_image() { # FILE W H
  oiiotool --info "$1" | grep -q "$2 x *$3" || { oiiotool --info "$1"; fail "$1 is not $2x$3"; }
  oiiotool --stats "$1" > stats.txt || fail "oiiotool --stats $1"
  python3 - stats.txt "$1" <<'PY' || fail "$1 is blank"
import sys
for line in open(sys.argv[1]):
    if "StdDev" in line:
        sd = [float(x) for x in line.split(":")[1].split()[:3]]
        assert max(sd) > 5, f"{sys.argv[2]}: stddev {sd}"
        break
else:
    raise SystemExit("no stats")
PY
}
check_image out/error_vs_time.png 900 600
check_image out/pass_times.png 900 600
oiiotool --info out/compare_scatter_vs_gather.png | grep -q "140 x *32" || fail "comparison image is not 4 panels of 32x32"
oiiotool --info -v -a out/compare_scatter_vs_gather.exr | grep -q "name: \"gather.indirect\"" || fail "comparison EXR lacks gather.indirect"
grep -q "<svg" out/error_vs_time.svg || fail "SVG chart is not SVG"

# Malformed configs: exit 2, one line naming the config, no results left behind.
expect_bad() { # NAME JSON [NAMED: the file at fault, default the config]
  printf '%s' "$2" > "$1"
  mkdir -p bad; echo stale > bad/bench.csv
  "$ISPM" bench "$1" -o bad --quiet > /dev/null 2> err.txt; rc=$?
  [ $rc -eq 2 ] || { cat err.txt; fail "$1: exit $rc, want 2"; }
  [ "$(wc -l < err.txt)" -eq 1 ] || { cat err.txt; fail "$1: want one error line"; }
  grep -qF "${3:-$1}" err.txt || { cat err.txt; fail "$1: error does not name ${3:-$1}"; }
  [ ! -f bad/bench.json ] || fail "$1: bench.json written"
}
GOOD_M='"methods": [{"name": "a", "settings": {"indirect": "ispm"}}]'
expect_bad trunc.json '{"sequence": "seq.json", "reference": "refrun", "frames": 1,'
expect_bad unknown.json "{\"sequence\": \"seq.json\", \"reference\": \"refrun\", \"frames\": 1, \"bogus\": 1, $GOOD_M}"
expect_bad nomethods.json '{"sequence": "seq.json", "reference": "refrun", "frames": 1}'
expect_bad badsetting.json "{\"sequence\": \"seq.json\", \"reference\": \"refrun\", \"frames\": 1, \"grid\": {\"photon_count\": [1024, -5]}, $GOOD_M}"
expect_bad badkey.json "{\"sequence\": \"seq.json\", \"reference\": \"refrun\", \"frames\": 1, \"grid\": {\"photon_cuont\": [1024]}, $GOOD_M}"
expect_bad badmethod.json '{"sequence": "seq.json", "reference": "refrun", "frames": 1, "methods": [{"name": "a", "settings": {"indirect": "raytrace"}}]}'
expect_bad both.json '{"sequence": "seq.json", "reference": "refrun", "frames": 1, "grid": {"indirect": ["ispm"]}, "methods": [{"name": "a", "settings": {"indirect": "ispm"}}]}'
expect_bad frame.json "{\"sequence\": \"seq.json\", \"reference\": \"refrun\", \"frames\": [5], $GOOD_M}"
expect_bad noref.json "{\"sequence\": \"seq.json\", \"reference\": \"seq.json\", \"frames\": 1, $GOOD_M}" seq.json
expect_bad dup.json '{"sequence": "seq.json", "reference": "refrun", "frames": 1, "methods": [{"name": "a"}, {"name": "a"}]}'
expect_bad p90full.json "{\"sequence\": \"seq.json\", \"reference\": \"refrun\", \"frames\": 1, \"chart\": {\"metric\": \"block_p90\", \"buffer\": \"full\"}, $GOOD_M}"
# A run that is not a reference run (no reference.* buffers).
"$ISPM" record seq.json -o plainrun --quiet > /dev/null || fail "record plain run"
expect_bad notref.json "{\"sequence\": \"seq.json\", \"reference\": \"plainrun\", \"frames\": 1, $GOOD_M}" plainrun
"$ISPM" bench > /dev/null 2>&1; [ $? -eq 2 ] || fail "bench without arguments must exit 2"
# --check: validates without a reference run or rendering; every config the project ships
# (bench/*.json, the README's tables come from them) must pass it.
"$ISPM" bench --check badsetting.json > /dev/null 2> err.txt; rc=$?
[ $rc -eq 2 ] && grep -qF badsetting.json err.txt || { cat err.txt; fail "bench --check of a bad config: exit $rc"; }
for f in "$SRC"/bench/*.json; do
  "$ISPM" bench --check "$f" > check.out 2> err.txt || { cat err.txt; fail "bench --check $f"; }
  grep -q " valid$" check.out || fail "bench --check $f printed: $(cat check.out)"
done
echo "e2e_bench: ok"
