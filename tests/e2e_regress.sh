#!/usr/bin/env bash
# The regression workflow end to end, on a small Cornell box (48x48, 2 frames):
#   - a settings change appears as a provenance line in every report format (warn; fails with
#     --provenance-fail); the tool's git revision is information only;
#   - idiff-style flags (-fail, --hardfail, ...) override the tolerance file; bad options exit 2;
#   - a reviewed bless: a new golden needs no flag and gets BLESS.md; a bit-exact re-bless changes
#     nothing; a run that differs is refused without --accept and nothing on disk in the golden
#     changes; with --accept it is replaced and BLESS.md names the change;
#   - timing: a pass made 2x slower (in the manifest) is reported and fails only with --timing-fail;
#   - ispm check: 0 good, 1 bad, 125 cannot judge.
# usage: e2e_regress.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK/s"
cp "$SRC/scenes/cornell-box/cornell-box.gltf" "$WORK/s/"
seq_with() { # seq_with FILE KERNEL_RADIUS
  printf '{"name": "regress-small", "scene": "cornell-box.gltf", "frames": 2, "fps": 8, "resolution": [48, 48],
  "camera": {"node": "Camera"}, "settings": {"shadow_map_size": 64, "photon_count": 2048, "kernel_radius": %s, "threads": 2},
  "capture": ["final.display", "indirect.radiance", "direct.radiance"]}\n' "$2" > "$1"
}
seq_with "$WORK/s/a.json" 0.15
seq_with "$WORK/s/b.json" 0.25
"$ISPM" record "$WORK/s/a.json" -o "$WORK/a" --quiet > /dev/null || fail "record a"
"$ISPM" record "$WORK/s/b.json" -o "$WORK/b" --quiet > /dev/null || fail "record b"
G=$WORK/golden/regress-small
tree_sum() { (cd "$1" && find . -type f -print0 | sort -z | xargs -0 md5sum; find . | sort) | md5sum; }

# --- bless: new golden, no flag; BLESS.md beside it.
"$ISPM" bless "$WORK/a" "$G" > "$WORK/bless1.txt" || fail "bless of a new golden exited $?"
[ -f "$G/BLESS.md" ] || fail "new golden has no BLESS.md"
grep -q "new golden" "$G/BLESS.md" || fail "BLESS.md of a new golden does not say so"
# a bit-exact re-bless is a no-op
before=$(tree_sum "$G")
"$ISPM" bless "$WORK/a" "$G" > "$WORK/bless2.txt" || fail "bit-exact re-bless exited $?"
grep -q "unchanged" "$WORK/bless2.txt" || { cat "$WORK/bless2.txt"; fail "bit-exact re-bless does not say unchanged"; }
[ "$before" = "$(tree_sum "$G")" ] || fail "bit-exact re-bless changed the golden"

# --- provenance: a settings change is a warn line in text, JSON, JUnit and HTML, before pixels.
"$ISPM" replay "$WORK/b" --golden "$G" > "$WORK/rb.txt"; rc=$?
[ $rc -eq 2 ] || { cat "$WORK/rb.txt"; fail "replay b vs a: exit $rc, want 2 (pixels differ)"; }
line=$(grep -n 'warn settings.kernel_radius: golden 0.15, run 0.25' "$WORK/rb.txt" | head -n 1 | cut -d: -f1)
[ -n "$line" ] || { cat "$WORK/rb.txt"; fail "no provenance line for the changed setting"; }
first_px=$(grep -n '^FAIL\|^WARN' "$WORK/rb.txt" | head -n 1 | cut -d: -f1)
[ -n "$first_px" ] && [ "$line" -lt "$first_px" ] || fail "provenance is not reported before pixels"
R=$WORK/b/replay
python3 - "$R/report.json" <<'EOF' || fail "report.json provenance"
import json, sys
r = json.load(open(sys.argv[1]))
d = {x["key"]: x for x in r["provenance"]["differences"]}
assert d["settings.kernel_radius"]["level"] == "warn", d
assert d["settings.kernel_radius"]["golden"] == "0.15" and d["settings.kernel_radius"]["run"] == "0.25"
assert all(x["level"] == "info" for k, x in d.items() if k.startswith("tool.")), d
assert r["timing"]["passes"], r["timing"]
EOF
grep -q 'name="provenance"' "$R/report.junit.xml" || fail "JUnit has no provenance test case"
grep -q 'settings.kernel_radius' "$R/report.junit.xml" || fail "JUnit does not name the changed setting"
grep -q 'id="provenance"' "$R/report.html" && grep -q 'settings.kernel_radius' "$R/report.html" || fail "HTML provenance"
# the same inputs (b against itself blessed elsewhere) give no provenance warn; a git revision is info
"$ISPM" bless "$WORK/b" "$WORK/golden/b" > /dev/null || fail "bless b"
cp -r "$WORK/b" "$WORK/b2"; rm -rf "$WORK/b2/replay"
sed -i 's/"git":[[:space:]]*"[^"]*"/"git": "0123456789ab"/' "$WORK/b2/manifest.json"
"$ISPM" replay "$WORK/b2" --golden "$WORK/golden/b" > "$WORK/rb2.txt"; rc=$?
[ $rc -eq 0 ] || { cat "$WORK/rb2.txt"; fail "a different git revision alone must not warn (exit $rc)"; }
grep -Eq 'info tool.git: golden "([0-9a-f]{12}(-dirty)?|unknown)", run "0123456789ab"' "$WORK/rb2.txt" || fail "git revision not reported as info"
# --provenance-fail: the settings change fails even with loose pixel thresholds
"$ISPM" replay "$WORK/b" --golden "$G" -fail 1e9 -hardfail 1e9 -warn 1e9 -hardwarn 1e9 > /dev/null; rc=$?
[ $rc -eq 1 ] || fail "settings change with loose thresholds: exit $rc, want 1 (provenance warns)"
"$ISPM" replay "$WORK/b" --golden "$G" -fail 1e9 -hardfail 1e9 -warn 1e9 -hardwarn 1e9 --provenance-fail > /dev/null; rc=$?
[ $rc -eq 2 ] || fail "--provenance-fail: exit $rc, want 2"

# --- idiff flags override the file: a file that fails everything, overridden on the command line.
printf '{"default": {"fail": 0, "failrelative": 0, "hardfail": 0, "warn": 0}}\n' > "$WORK/strict.json"
"$ISPM" replay "$WORK/b" --golden "$G" --tolerances "$WORK/strict.json" > /dev/null; rc=$?
[ $rc -eq 2 ] || fail "strict file: exit $rc, want 2"
"$ISPM" replay "$WORK/b" --golden "$G" --tolerances "$WORK/strict.json" -fail 1e9 --failrelative 1e9 -hardfail 1e9 \
  > "$WORK/flags.txt"; rc=$?
[ $rc -eq 1 ] || { cat "$WORK/flags.txt"; fail "-fail over the file: exit $rc, want 1 (warnings only)"; }
grep -q 'overridden by -fail 1e+09 -failrelative 1e+09 -hardfail 1e+09' "$WORK/flags.txt" || fail "report does not show the flags"
grep -q '^FAIL' "$WORK/flags.txt" && fail "-fail did not override the file"
# bad options exit 2, like every other command
"$ISPM" replay "$WORK/b" --golden "$G" --frobnicate > /dev/null 2>&1; [ $? -eq 2 ] || fail "unknown option: want exit 2"
"$ISPM" replay "$WORK/b" --golden "$G" -fail abc > /dev/null 2>&1; [ $? -eq 2 ] || fail "-fail abc: want exit 2"
"$ISPM" replay "$WORK/b" --golden "$G" --frames 3-1 > /dev/null 2>&1; [ $? -eq 2 ] || fail "--frames 3-1: want exit 2"
# --frames / --buffers narrow the comparison
"$ISPM" replay "$WORK/b" --golden "$G" --frames 1-1 --buffers 'final.*' --report "$WORK/narrow" > "$WORK/narrow.txt"
python3 - "$WORK/narrow/report.json" <<'EOF' || fail "--frames/--buffers"
import json, sys
r = json.load(open(sys.argv[1]))
names = [(f["index"], b["name"]) for f in r["frames"] for b in f["buffers"]]
assert names == [(1, "final.display")], names
EOF

# --- reviewed bless: refused without --accept, nothing in the golden changes.
before=$(tree_sum "$G")
"$ISPM" bless "$WORK/b" "$G" > "$WORK/bless3.txt"; rc=$?
[ $rc -eq 1 ] || { cat "$WORK/bless3.txt"; fail "bless of a differing run without --accept: exit $rc, want 1"; }
[ "$before" = "$(tree_sum "$G")" ] || fail "a refused bless changed the golden"
grep -q 'settings.kernel_radius' "$WORK/bless3.txt" || fail "refused bless does not show the provenance change"
grep -q "bless $WORK/b $G --accept" "$WORK/bless3.txt" || fail "refused bless does not give the command to accept"
[ -f "$WORK/b/bless/report.html" ] || fail "no HTML review"
"$ISPM" bless "$WORK/b" "$G" --accept > "$WORK/bless4.txt" || fail "bless --accept exited $?"
grep -q 'settings.kernel_radius' "$G/BLESS.md" || fail "BLESS.md does not record the provenance change"
grep -q 'What changes' "$G/BLESS.md" || fail "BLESS.md does not list what changes"
[ "$(wc -c < "$G/BLESS.md")" -lt 20000 ] || fail "BLESS.md is too large for a committed golden"
"$ISPM" replay "$WORK/b" --golden "$G" > /dev/null || fail "replay after an accepted bless"

# --- timing: one pass 2x slower in every frame (its share ratio is ~2 for a small pass).
cp -r "$WORK/b" "$WORK/slow"; rm -rf "$WORK/slow/replay" "$WORK/slow/bless"
python3 - "$WORK/slow/manifest.json" <<'EOF'
import json, sys
m = json.load(open(sys.argv[1]))
for f in m["frames"]:
    for p in f["passes"]:
        if p["name"] == "gbuffer":
            p["ms"] *= 2
json.dump(m, open(sys.argv[1], "w"), indent=1)
EOF
"$ISPM" replay "$WORK/slow" --golden "$G" > "$WORK/slow.txt"; rc=$?
[ $rc -eq 0 ] || { cat "$WORK/slow.txt"; fail "a slower pass must not fail without --timing-fail (exit $rc)"; }
grep -qE '^ +gbuffer .*×(1\.[5-9]|2\.0)' "$WORK/slow.txt" || { cat "$WORK/slow.txt"; fail "the 2x slower pass is not reported"; }
"$ISPM" replay "$WORK/slow" --golden "$G" --timing-fail 1.4 > "$WORK/slow2.txt"; rc=$?
[ $rc -eq 2 ] || { cat "$WORK/slow2.txt"; fail "--timing-fail 1.4: exit $rc, want 2"; }
grep -qE 'FAIL +gbuffer' "$WORK/slow2.txt" || fail "--timing-fail does not name the pass"
"$ISPM" replay "$WORK/b" --golden "$G" --timing-fail 1.4 > /dev/null || fail "--timing-fail fails an unchanged run"

# --- ispm check: good, bad, cannot judge.
"$ISPM" check "$WORK/s/b.json" --golden "$G" --quiet > "$WORK/c1.txt"; rc=$?
[ $rc -eq 0 ] || { cat "$WORK/c1.txt"; fail "check of the blessed sequence: exit $rc, want 0"; }
"$ISPM" check "$WORK/s/a.json" --golden "$G" --quiet > "$WORK/c2.txt"; rc=$?
[ $rc -eq 1 ] || { cat "$WORK/c2.txt"; fail "check of a regressed sequence: exit $rc, want 1"; }
"$ISPM" check "$WORK/s/a.json" --golden "$WORK/nowhere" > /dev/null 2>&1; rc=$?
[ $rc -eq 125 ] || fail "check without a golden: exit $rc, want 125"
"$ISPM" check "$WORK/s/missing.json" --golden "$G" > /dev/null 2>&1; rc=$?
[ $rc -eq 125 ] || fail "check of a missing sequence: exit $rc, want 125"
# --- info and export
"$ISPM" info "$WORK/b" > "$WORK/info.txt" || fail "info exited $?"
grep -q '^frames: 2 at 48x48' "$WORK/info.txt" || fail "info: frames"
grep -q 'final.display .*48x48 *R,G,B' "$WORK/info.txt" || fail "info: buffers"
grep -q 'kernel_radius *0.25' "$WORK/info.txt" || fail "info: settings"
grep -q '^last replay: OK against' "$WORK/info.txt" || fail "info: last verdict"
# The passes' times: frame 0, median of the later frames and sum, as the manifest holds them
# (the run whose gbuffer pass was doubled above).
"$ISPM" info "$WORK/slow" > "$WORK/info-slow.txt" || fail "info of the slowed run exited $?"
want=$(python3 - "$WORK/slow/manifest.json" <<'EOF'
import json, statistics, sys
m = json.load(open(sys.argv[1]))
for name in ("gbuffer", "splat"):
    ms = [p["ms"] for f in m["frames"] for p in f["passes"] if p["name"] == name]
    print("%s %.1f %.1f %.1f" % (name, ms[0], statistics.median(ms[1:]), sum(ms)))
EOF
)
got=$(awk '/^passes \(ms\)/ { on = 1; next } on && /^  (gbuffer|splat) / { print $1, $2, $3, $4 } on && !/^  / { on = 0 }' "$WORK/info-slow.txt")
[ -n "$want" ] && [ "$got" = "$want" ] || { cat "$WORK/info-slow.txt"; fail "info: pass times '$got', want '$want'"; }
"$ISPM" info "$WORK/nowhere" > /dev/null 2>&1; [ $? -eq 2 ] || fail "info of a missing run: want exit 2"
"$ISPM" export "$WORK/b" --frame 1 --buffer final.display -o "$WORK/f1.png" > /dev/null || fail "export png"
[ "$(head -c 4 "$WORK/f1.png" | tail -c 3)" = "PNG" ] || fail "export did not write a PNG"
"$ISPM" export "$WORK/b" --frame 1 --buffer indirect.radiance -o "$WORK/i1.exr" > /dev/null || fail "export exr"
[ "$(head -c 4 "$WORK/i1.exr" | od -An -tx1 | tr -d ' ')" = "762f3101" ] || fail "export did not write an EXR"
"$ISPM" export "$WORK/b" --frame 5 --buffer final.display -o "$WORK/x.png" > /dev/null 2>&1; [ $? -eq 2 ] || fail "export of a missing frame: want 2"
"$ISPM" export "$WORK/b" --frame 1 --buffer nope -o "$WORK/x.png" > /dev/null 2>&1; [ $? -eq 2 ] || fail "export of a missing buffer: want 2"
echo "e2e_regress: ok"
