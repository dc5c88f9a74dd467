#!/usr/bin/env bash
# Real glTF files as a new user meets them: every file of bench/gltf-corpus.list recorded once
# (1 frame, 64x48, no camera in the sequence so the scene is framed, one directional light
# added so that files without lights are lit), then one table: loaded, refused (the first line
# of stderr, sorted into kinds), crashed or timed out, black or clipped final.display (measured
# here from the exported PNG, independently of the capture's own check) and whether the run
# warned about it, and the time of each record.
#
# The corpus lives outside the repository: bench/gltf-corpus.list names each file as
# "<owner>/<repo>@<commit> <path>"; CORPUS holds <owner>+<repo>/<path>, made with e.g.
#   git clone https://github.com/<owner>/<repo> && git -C <repo> archive <commit> | tar -x -C CORPUS/<owner>+<repo>
# usage: bench/gltf-corpus.sh ISPM CORPUS [OUTDIR]   (TIMEOUT=120 s per file, JOBS=1; EXPOSURE=auto
# or a number sets the sequences' "exposure"; LIST=FILE another list, e.g. the clipped files)
set -u
ISPM=$(readlink -f "$1"); CORPUS=$(readlink -f "$2"); OUT=${3:-out/gltf-corpus}
TIMEOUT=${TIMEOUT:-120}; JOBS=${JOBS:-1}
LIST=${LIST:-$(dirname "$0")/gltf-corpus.list}
mkdir -p "$OUT"; OUT=$(readlink -f "$OUT")
one() { # one INDEX SOURCE PATH
  local i=$1 src=$2 path=$3
  local dir="$OUT/$i" repo="${src%@*}"
  local file="$CORPUS/${repo/\//+}/$path"
  rm -rf "$dir"; mkdir -p "$dir"
  python3 -c 'import json,sys; s={"scene": sys.argv[1], "frames": 1, "fps": 1,
    "resolution": [64, 48], "settings": {"shadow_map_size": 128, "photon_count": 2000, "threads": 1},
    "lights": [{"type": "directional", "direction": [-0.3, -1, -0.5], "intensity": 3}],
    "capture": ["final.display"]}
e = sys.argv[2]
if e: s["settings"]["exposure"] = e if e == "auto" else float(e)
print(json.dumps(s))' "$file" "${EXPOSURE:-}" > "$dir/seq.json"
  local t0 t1 rc
  t0=$(date +%s.%N)
  nice -n 10 timeout "$TIMEOUT" "$ISPM" record "$dir/seq.json" -o "$dir/run" --quiet > /dev/null 2> "$dir/err"
  rc=$?
  t1=$(date +%s.%N)
  echo "$rc $(echo "$t1 - $t0" | bc)" > "$dir/rc"
  if [ "$rc" = 0 ]; then
    "$ISPM" export "$dir/run" --frame 0 --buffer final.display -o "$dir/display.png" > /dev/null 2>&1
    rm -rf "$dir/run/frames"/*.exr
  fi
}
i=0
while read -r src path; do
  case "$src" in ''|'#'*) continue ;; esac
  i=$((i + 1))
  [ -f "$OUT/$i/rc" ] && [ -z "${RERUN:-}" ] && continue
  one "$i" "$src" "$path" &
  while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do wait -n; done
done < "$LIST"
wait
python3 - "$LIST" "$OUT" <<'PY'
import json, os, re, statistics, struct, sys, zlib
lst, out = sys.argv[1], sys.argv[2]
def png_pixels(p):
    """8-bit RGB/RGBA non-interlaced PNG (what ispm export writes) -> rows of (r, g, b)."""
    b = open(p, "rb").read()
    at, idat, w = 8, b"", 0
    while at < len(b):
        n, t = struct.unpack(">I4s", b[at:at + 8])
        d = b[at + 8:at + 8 + n]
        if t == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", d[:10])
            ch = {2: 3, 6: 4}[ctype]
        elif t == b"IDAT":
            idat += d
        at += 12 + n
    raw, stride, rows, prev = zlib.decompress(idat), w * ch, [], bytearray(w * ch)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - ch] if x >= ch else 0
            up, c = prev[x], (prev[x - ch] if x >= ch else 0)
            if f == 1: line[x] = (line[x] + a) & 255
            elif f == 2: line[x] = (line[x] + up) & 255
            elif f == 3: line[x] = (line[x] + (a + up) // 2) & 255
            elif f == 4:
                pa, pb, pc = abs(up - c), abs(a - c), abs(a + up - 2 * c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else up if pb <= pc else c)) & 255
        rows.append([tuple(line[x * ch:x * ch + 3]) for x in range(w)])
        prev = line
    return rows
def kind(msg):
    rules = [("no geometry", "no geometry"), ("glTF 1.0", "glTF 1.0"), ("GLB container of version 1", "glTF 1.0"),
             ("extensionsRequired", "required extension not read"), ("asset.version", "glTF version"),
             ("no such file beside", "a file the glTF names is missing"), ("image ", "image"),
             ("out of range", "index out of range"), ("json.exception", "not JSON / bad JSON"),
             ("JSON", "not JSON / bad JSON"), ("buffer", "buffer/accessor layout"), ("accessor", "buffer/accessor layout"),
             ("lights", "lights"), ("camera", "camera")]
    for k, v in rules:
        if k in msg:
            return v
    return "other"
rows, i = [], 0
for line in open(lst):
    if not line.strip() or line.startswith("#"):
        continue
    i += 1
    src, path = line.split(None, 1)
    d = "%s/%d" % (out, i)
    if not os.path.exists(d + "/rc"):
        continue
    rc, t = open(d + "/rc").read().split()
    rc, t = int(rc), float(t)
    err = open(d + "/err", errors="replace").read().splitlines()
    r = {"i": i, "file": src.split("@")[0] + "/" + path.strip(), "rc": rc, "time": t}
    if rc in (124, 137) or rc >= 128:
        r["state"] = "timeout" if rc in (124, 137) else "crash"
    elif rc != 0:
        r["state"] = "refused"
        r["why"] = err[0] if err else "(nothing on stderr)"
        r["kind"] = kind(r["why"])
        r["one_line"] = len([e for e in err if e.strip()]) == 1
    else:
        r["state"] = "loaded"
        m = json.load(open(d + "/run/manifest.json"))
        r["warned"] = m["frames"][0].get("display_warning", "")
        px = [p for row in png_pixels(d + "/display.png") for p in row] if os.path.exists(d + "/display.png") else []
        r["black"] = bool(px) and all(max(p) == 0 for p in px)
        r["clipped"] = sum(1 for p in px if max(p) == 255) / max(len(px), 1)
        r["white"] = sum(1 for p in px if min(p) == 255) / max(len(px), 1)
        r["exposure"] = m["settings"].get("exposure")
    rows.append(r)
json.dump(rows, open(out + "/corpus.json", "w"), indent=1)
loaded = [r for r in rows if r["state"] == "loaded"]
refused = [r for r in rows if r["state"] == "refused"]
bad = [r for r in rows if r["state"] in ("crash", "timeout")]
black = [r for r in loaded if r["black"]]
# clipped as the capture's warning counts it (more than 5 % of the pixels white in every channel),
# and, as a wider net, more than 2 % with any channel at 255
clipped = [r for r in loaded if r["white"] > 0.05]
any_clip = [r for r in loaded if r["clipped"] > 0.02]
silent = [r for r in black + clipped if not r["warned"]]
print("files %d: loaded %d, refused %d, crashed or timed out %d" % (len(rows), len(loaded), len(refused), len(bad)))
kinds = {}
for r in refused:
    kinds.setdefault(r["kind"], []).append(r)
for k, v in sorted(kinds.items(), key=lambda kv: -len(kv[1])):
    print("  refused, %-34s %3d  e.g. %s" % (k + ":", len(v), v[0]["why"][:150]))
print("refusals not one line: %d" % sum(1 for r in refused if not r["one_line"]))
print("black %d, clipped (> 5%% white) %d, of them without a warning %d" % (len(black), len(clipped), len(silent)))
for r in silent:
    print("  SILENT: %s" % r["file"])
print("any channel at 255 on > 2%% of the pixels: %d (%d of them warned)" % (len(any_clip),
      sum(1 for r in any_clip if r["warned"])))
for r in clipped + [r for r in any_clip if r not in clipped]:
    print("  clipped: %s: %.1f %% white, %.1f %% any channel, exposure %s%s" % (r["file"], 100 * r["white"],
          100 * r["clipped"], r["exposure"], ", warned" if r["warned"] else ""))
for r in bad:
    print("  %s: %s (exit %d)" % (r["state"].upper(), r["file"], r["rc"]))
ts = sorted(r["time"] for r in loaded)
if ts:
    print("record time of loaded files: median %.2f s, max %.2f s (%s)" % (statistics.median(ts), ts[-1],
          max(loaded, key=lambda r: r["time"])["file"]))
with open(out + "/corpus.tsv", "w") as f:
    f.write("file\tstate\ttime_s\tblack\tclipped\twarning_or_refusal\n")
    for r in rows:
        f.write("%s\t%s\t%.2f\t%s\t%s\t%s\n" % (r["file"], r["state"], r["time"], r.get("black", ""),
                "%.3f" % r["clipped"] if "clipped" in r else "", r.get("warned") or r.get("why", "")))
print("table: %s/corpus.tsv" % out)
PY
