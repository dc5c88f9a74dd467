#!/usr/bin/env bash
# Hostile inputs and unlucky states, one case per class of docs/inputs.md: crashes (a glTF nested
# 20,000 deep), hangs (FIFOs as the sequence, a bench config's sequence, a golden manifest; a
# frame of 512 MB of zeros; a frame linked to an 8 GB sparse file), memory (a frame of 16384²
# ZIP parts, an 8 GB sparse .bin, PNG textures of 16384² and 30000²), reading outside (a
# symlinked tolerances.json blessed, a symlinked shard frame merged, text after a manifest's
# JSON), lost data (merge onto its own shard, export onto a full disk, a bless killed between
# its renames), locks (bless and record into a folder in use) and silent fallbacks (tolerance
# files that are FIFOs, dangling links, out of range or with a bad glob; --pixel that wraps;
# JSON too deep; a sparse count of 2^31; a report that cannot be written; a tampered shard
# merged), and record --force and merge --force onto a complete run on a full disk. Every fixture is made here at run time (sparse files
# and FIFOs cost no disk). Every command runs under `timeout 10` and /usr/bin/time: it must end
# with the expected exit code, exactly one line on stderr naming the file, and a peak RSS under
# 1.5 GB. Prints one line per case with its time and peak RSS.
# usage: e2e_hostile.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$(realpath "$1"); SRC=$(realpath "$2"); WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
[ -x /usr/bin/time ] || { echo "SKIP: /usr/bin/time (Debian package time) is not installed"; exit 77; }
command -v python3 > /dev/null || { echo "SKIP: python3 is needed to write the fixtures"; exit 77; }
rm -rf "$WORK"; mkdir -p "$WORK"
W=$WORK
SCENE=$SRC/scenes/cornell-box/cornell-box.gltf
RSS_MAX_KB=1572864 # 1.5 GiB
CASES=0

# expect NAME CODE NAMED CMD...: CMD ends within 10 s with exit CODE, one line on stderr naming
# NAMED, and a peak RSS under RSS_MAX_KB.
expect() {
  name=$1; code=$2; named=$3; shift 3
  start=$(date +%s.%N)
  timeout 10 /usr/bin/time -f "%M" -o "$W/rss.txt" "$@" > "$W/out.txt" 2> "$W/err.txt"; rc=$?
  end=$(date +%s.%N)
  [ $rc -ne 124 ] || fail "$name: still running after 10 s"
  [ $rc -eq "$code" ] || { cat "$W/err.txt"; fail "$name: exit $rc, want $code"; }
  # /usr/bin/time appends its own line to stderr only for a signal; the command's is the first.
  [ "$(wc -l < "$W/err.txt")" -eq 1 ] || { cat "$W/err.txt"; fail "$name: want one line on stderr"; }
  grep -qF -- "$named" "$W/err.txt" || { cat "$W/err.txt"; fail "$name: the error does not name $named"; }
  rss=$(tail -n 1 "$W/rss.txt")
  [ "$rss" -lt $RSS_MAX_KB ] || fail "$name: peak RSS $rss KB"
  CASES=$((CASES + 1))
  printf '%-44s exit %d  %5.2f s  %7d KB  %s\n' "$name" "$rc" "$(echo "$end - $start" | bc)" "$rss" "$(head -c 110 "$W/err.txt")"
}
seq_with() { # seq_with FILE SCENE [FRAMES]
  printf '{"scene": "%s", "frames": %s, "fps": 8, "resolution": [32, 24], "camera": {"node": "Camera"},
 "settings": {"shadow_map_size": 16, "photon_count": 256, "exposure": -1}}\n' "$2" "${3:-2}" > "$1"
}
same() { cmp -s "$1" "$2"; }

# ---- fixtures: a good run, its golden, two shards
seq_with "$W/tiny.json" "$SCENE"
"$ISPM" record "$W/tiny.json" -o "$W/run" --quiet > /dev/null || fail "record the fixture run"
"$ISPM" bless "$W/run" "$W/gold" > /dev/null || fail "bless the fixture golden"
"$ISPM" record "$W/tiny.json" -o "$W/shardA" --frames 0-0 --quiet > /dev/null || fail "record shard A"
"$ISPM" record "$W/tiny.json" -o "$W/shardB" --frames 1-1 --quiet > /dev/null || fail "record shard B"
golden() { rm -rf "$W/$1"; cp -r "$W/gold" "$W/$1"; }
run_copy() { rm -rf "$W/$1"; cp -r "$W/run" "$W/$1"; }
truncate -s 8G "$W/sparse8g"

# ---- crash: tinygltf's recursive JSON parser
python3 -c "
import sys
n = 20000
open(sys.argv[1], 'w').write('{\"asset\": {\"version\": \"2.0\"}, \"extras\": ' + '[' * n + ']' * n + '}')" "$W/deep.gltf"
seq_with "$W/deep.json" "$W/deep.gltf"
expect "glTF extras nested 20,000 deep" 2 "deep.gltf: byte" "$ISPM" record "$W/deep.json" -o "$W/r" --quiet

# ---- hangs
mkfifo "$W/seq.fifo"
expect "sequence argument is a FIFO" 2 "seq.fifo: is a FIFO" "$ISPM" record "$W/seq.fifo" -o "$W/r" --quiet
printf '{"sequence": "%s", "reference": "%s", "frames": [0], "methods": [{"name": "ispm", "settings": {}}]}\n' "$W/seq.fifo" "$W/run" > "$W/bench.json"
expect "bench config's sequence is a FIFO" 2 "seq.fifo: is a FIFO" "$ISPM" bench "$W/bench.json" -o "$W/bench" --quiet
golden gfifo; rm "$W/gfifo/manifest.json"; mkfifo "$W/gfifo/m.fifo"; ln -s m.fifo "$W/gfifo/manifest.json"
expect "golden manifest.json linked to a FIFO" 4 "gfifo/manifest.json: is a symbolic link" \
  "$ISPM" replay "$W/run" --golden "$W/gfifo" --report "$W/rep"
golden gzeros; rm "$W/gzeros/frames/000000.exr"; truncate -s 512M "$W/gzeros/frames/000000.exr"
expect "golden frame of 512 MB of zeros" 4 "000000.exr: file is 536870912 bytes" \
  "$ISPM" replay "$W/run" --golden "$W/gzeros" --report "$W/rep"
golden gnotexr; head -c 5000 /dev/urandom > "$W/gnotexr/frames/000000.exr"
expect "golden frame that is not an EXR" 4 "000000.exr: not an OpenEXR file" \
  "$ISPM" replay "$W/run" --golden "$W/gnotexr" --report "$W/rep"
golden glink; rm "$W/glink/frames/000000.exr"; ln -s "$W/sparse8g" "$W/glink/frames/000000.exr"
expect "golden frame linked to an 8 GB sparse file" 4 "000000.exr: is a symbolic link" \
  "$ISPM" replay "$W/run" --golden "$W/glink" --report "$W/rep"

# ---- memory: an EXR of PARTS scanline ZIP parts of SIDE² float zeros (~1 KB a chunk)
exr_bomb() { # exr_bomb FILE PARTS SIDE
  python3 - "$@" << 'EOF'
import struct, sys, zlib
path, parts, side = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
def attr(name, typ, value):
    return name.encode() + b'\0' + typ.encode() + b'\0' + struct.pack('<i', len(value)) + value
chunks = (side + 15) // 16
raw = 16 * side * 4  # ZIP's predictor turns zeros into 0, 128, 128, ...
data = zlib.compress(bytes([0]) + bytes([128]) * (raw - 1), 9)
heads = b''
for p in range(parts):
    box = struct.pack('<iiii', 0, 0, side - 1, side - 1)
    heads += (attr('name', 'string', b'bomb%d' % p) + attr('type', 'string', b'scanlineimage') +
              attr('channels', 'chlist', b'Y\0' + struct.pack('<iB3xii', 2, 0, 1, 1) + b'\0') +
              attr('compression', 'compression', b'\x03') + attr('dataWindow', 'box2i', box) +
              attr('displayWindow', 'box2i', box) + attr('lineOrder', 'lineOrder', b'\0') +
              attr('pixelAspectRatio', 'float', struct.pack('<f', 1)) +
              attr('screenWindowCenter', 'v2f', struct.pack('<ff', 0, 0)) +
              attr('screenWindowWidth', 'float', struct.pack('<f', 1)) +
              attr('chunkCount', 'int', struct.pack('<i', chunks)) + b'\0')
head = b'\x76\x2f\x31\x01' + struct.pack('<I', 2 | 0x1000) + heads + b'\0'
table_len = 8 * chunks * parts
chunk_len = 12 + len(data)
offsets = b''.join(struct.pack('<Q', len(head) + table_len + (p * chunks + c) * chunk_len)
                   for p in range(parts) for c in range(chunks))
body = b''.join(struct.pack('<iii', p, c * 16, len(data)) + data for p in range(parts) for c in range(chunks))
open(path, 'wb').write(head + offsets + body)
EOF
}
golden gbomb8; exr_bomb "$W/gbomb8/frames/000000.exr" 8 16384
expect "golden frame of 8 ZIP parts of 16384² zeros" 4 "gbomb8/frames/000000.exr: file is" \
  "$ISPM" replay "$W/run" --golden "$W/gbomb8" --report "$W/rep"
golden gbomb1; exr_bomb "$W/gbomb1/frames/000000.exr" 1 16384
expect "golden frame of 1 ZIP part of 16384² zeros" 4 "bomb0: 16384x16384x1 floats, more than" \
  "$ISPM" replay "$W/run" --golden "$W/gbomb1" --report "$W/rep"
golden gparts; exr_bomb "$W/gparts/frames/000000.exr" 3 16
expect "golden frame whose parts the manifest lacks" 4 "gparts/frames/000000.exr: holds 3 parts" \
  "$ISPM" replay "$W/run" --golden "$W/gparts" --report "$W/rep"
mkdir -p "$W/ext"
ln -s "$W/sparse8g" "$W/ext/big.bin"
printf '{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 36, "uri": "big.bin"}]}\n' > "$W/ext/linked.gltf"
seq_with "$W/ext/linked.json" "$W/ext/linked.gltf"
expect "external .bin linked out of the folder" 2 "big.bin" "$ISPM" record "$W/ext/linked.json" -o "$W/r" --quiet
truncate -s 8G "$W/ext/huge.bin"
printf '{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 36, "uri": "huge.bin"}]}\n' > "$W/ext/huge.gltf"
seq_with "$W/ext/huge.json" "$W/ext/huge.gltf"
expect "external .bin of 8 GB (sparse)" 2 "huge.bin: file is 8589934592 bytes" \
  "$ISPM" record "$W/ext/huge.json" -o "$W/r" --quiet
png_header() { # png_header FILE W H: a PNG signature and IHDR (the rest of the file missing)
  python3 -c "
import struct, sys, zlib
ihdr = b'IHDR' + struct.pack('>IIBBBBB', int(sys.argv[2]), int(sys.argv[3]), 8, 6, 0, 0, 0)
open(sys.argv[1], 'wb').write(b'\x89PNG\r\n\x1a\n' + struct.pack('>I', 13) + ihdr + struct.pack('>I', zlib.crc32(ihdr)))
" "$@"
}
tex_scene() { # tex_scene FILE IMAGE: a textured triangle (only an image a drawn material uses is decoded)
  python3 - "$1" "$2" <<'PYEOF'
import base64, json, struct, sys
data = struct.pack('<9f', 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack('<6f', 0, 0, 1, 0, 0, 1)
gltf = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}], "images": [{"uri": sys.argv[2]}],
        "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}]}
open(sys.argv[1], "w").write(json.dumps(gltf))
PYEOF
}
seq_framed() { # seq_framed FILE SCENE: as seq_with, framed on the scene's bounds (no camera node)
  printf '{"scene": "%s", "frames": 1, "fps": 8, "resolution": [32, 24],
 "settings": {"shadow_map_size": 16, "photon_count": 256}}\n' "$2" > "$1"
}
for side in 16384 30000; do
  png_header "$W/ext/tex$side.png" $side $side
  tex_scene "$W/ext/tex$side.gltf" "tex$side.png"
  seq_framed "$W/ext/tex$side.json" "$W/ext/tex$side.gltf"
  expect "PNG texture of ${side}²" 2 "${side}x${side}, over the limit of 8192" \
    "$ISPM" record "$W/ext/tex$side.json" -o "$W/r" --quiet
done

# ---- reading outside, writing into a golden
echo '{"default": {"warn": 0.5}, "buffers": [], "SECRET": "outside"}' > "$W/secret.json"
golden gsym; rm "$W/gsym/tolerances.json"; ln -s "$W/secret.json" "$W/gsym/tolerances.json"
expect "bless into a golden whose tolerances.json is a link" 2 "gsym/tolerances.json: is a symbolic link" \
  "$ISPM" bless "$W/run" "$W/gsym" --accept
grep -rq SECRET "$W/gsym/" --exclude=tolerances.json && fail "the linked file's content reached the golden"
[ -L "$W/gsym/tolerances.json" ] || fail "the golden was replaced"
rm -rf "$W/shardL"; cp -r "$W/shardA" "$W/shardL"; rm "$W/shardL/frames/000000.exr"
ln -s "$W/shardA/frames/000000.exr" "$W/shardL/frames/000000.exr"
expect "merge of a shard whose frame is a link" 2 "shardL/frames/000000.exr: is a symbolic link" \
  "$ISPM" merge "$W/shardL" "$W/shardB" -o "$W/merged"
[ ! -e "$W/merged/manifest.json" ] || fail "a merged run was written from a linked frame"
run_copy rtrail; printf ' SECRET' >> "$W/rtrail/manifest.json"
expect "text after a manifest's JSON" 4 "rtrail/manifest.json: byte" \
  "$ISPM" replay "$W/rtrail" --golden "$W/gold" --report "$W/rep"

# ---- lost or half-written data
sha_b=$(cat "$W/shardB/manifest.json" "$W/shardB/frames/"* | sha256sum)
expect "merge A B -o B --force" 2 "refusing to write into an input" \
  "$ISPM" merge "$W/shardA" "$W/shardB" -o "$W/shardB" --force
[ "$(cat "$W/shardB/manifest.json" "$W/shardB/frames/"* | sha256sum)" = "$sha_b" ] || fail "shard B changed"
"$ISPM" merge "$W/shardA" "$W/shardB" -o "$W/merged" > /dev/null || fail "merge the shards"
sha_m=$(cat "$W/merged/manifest.json" "$W/merged/frames/"* | sha256sum)
# --force onto a complete run on a full disk (a file-size limit of 1 KB, less than run.json):
# the old run stays whole.
expect "merge --force onto a run, disk full" 1 "merged.merging/run.json" \
  bash -c 'trap "" XFSZ; ulimit -f 1; exec "$@"' - "$ISPM" merge "$W/shardA" "$W/shardB" -o "$W/merged" --force
[ "$(cat "$W/merged/manifest.json" "$W/merged/frames/"* | sha256sum)" = "$sha_m" ] || fail "merge --force: the old run changed"
[ ! -e "$W/merged.merging" ] || fail "merge --force left its temporary run"
"$ISPM" merge "$W/shardA" "$W/shardB" -o "$W/merged" --force > /dev/null || fail "merge --force onto a complete run"
"$ISPM" replay "$W/merged" --golden "$W/gold" --report "$W/rep" > /dev/null || fail "the merged run (--force) does not replay"
run_copy rforce; sha_r=$(cat "$W/rforce/manifest.json" "$W/rforce/frames/"* | sha256sum)
expect "record --force onto a run, disk full" 1 "rforce.recording/frames/000000.exr" \
  bash -c 'trap "" XFSZ; ulimit -f 20; exec "$@"' - "$ISPM" record "$W/tiny.json" -o "$W/rforce" --force --quiet
[ "$(cat "$W/rforce/manifest.json" "$W/rforce/frames/"* | sha256sum)" = "$sha_r" ] || fail "record --force: the old run changed"
[ ! -e "$W/rforce.recording" ] || fail "record --force left its temporary run"
# A record --force killed between its swap's renames: RUN.replaced, no RUN.
run_copy rswap; mv "$W/rswap" "$W/rswap.replaced"; sha_s=$(cat "$W/rswap.replaced/manifest.json" | sha256sum)
expect "replay of a run in an interrupted swap" 4 "an interrupted record or merge --force left" \
  "$ISPM" replay "$W/rswap" --golden "$W/gold" --report "$W/rep"
# The next writer puts it back (and, without --force, then refuses to replace it).
"$ISPM" merge "$W/shardA" "$W/shardB" -o "$W/rswap" > /dev/null 2> "$W/err.txt"
grep -q "an interrupted replacement was rolled back" "$W/err.txt" || { cat "$W/err.txt"; fail "no roll-back named"; }
[ "$(cat "$W/rswap/manifest.json" | sha256sum)" = "$sha_s" ] && [ ! -e "$W/rswap.replaced" ] || \
  fail "the interrupted swap was not rolled back"
CASES=$((CASES + 1)); echo "merge into a run in an interrupted swap: rolled back"
for ext in png exr; do
  "$ISPM" export "$W/run" --frame 0 --buffer final.display -o "$W/out.$ext" > /dev/null || fail "export .$ext"
  cp "$W/out.$ext" "$W/out.$ext.before"
  # A full disk: a file-size limit of 1 KB (SIGXFSZ ignored, so writes fail with EFBIG).
  expect "export -o .$ext onto a full disk" 1 "out.$ext" \
    bash -c 'trap "" XFSZ; ulimit -f 1; exec "$@"' - "$ISPM" export "$W/run" --frame 0 --buffer final.display -o "$W/out.$ext"
  same "$W/out.$ext" "$W/out.$ext.before" || fail "export .$ext: the old file was not kept"
  ls "$W" | grep -q "out.$ext.tmp" && fail "export .$ext left its temporary file"
done
# A bless killed between its two renames: <golden>.old and <golden>.tmp, no golden.
golden gkill; echo '{"default": {"warn": 0.25}, "buffers": []}' > "$W/gkill/tolerances.json"
cp "$W/gkill/tolerances.json" "$W/tuned.json"
mv "$W/gkill" "$W/gkill.old"; cp -r "$W/gold" "$W/gkill.tmp"
expect "replay against a golden in an interrupted bless" 4 "an interrupted bless left" \
  "$ISPM" replay "$W/run" --golden "$W/gkill" --report "$W/rep"
"$ISPM" bless "$W/run" "$W/gkill" > "$W/out.txt" 2> "$W/err.txt" || { cat "$W/err.txt"; fail "bless after an interrupted bless"; }
grep -q "rolled back" "$W/err.txt" || fail "the interrupted bless was not named"
same "$W/gkill/tolerances.json" "$W/tuned.json" || fail "the tuned tolerances were lost"
[ ! -e "$W/gkill.old" ] && [ ! -e "$W/gkill.tmp" ] || fail "the interrupted bless's folders were left"
grep -q "new golden" "$W/out.txt" && fail "bless made a new golden without review"
CASES=$((CASES + 1)); echo "bless killed between its renames: rolled back, tuned tolerances kept"

# ---- locks
golden glock; echo "ispm bless, process 4242" > "$W/glock.lock"
flock "$W/glock.lock" sleep 8 & holder=$!
for _ in $(seq 50); do flock -n "$W/glock.lock" true || break; sleep 0.1; done
expect "bless into a golden being blessed" 2 "in use by ispm bless, process 4242" \
  "$ISPM" bless "$W/run" "$W/glock" --accept
echo "ispm record, process 4343" > "$W/run.lock"
flock "$W/run.lock" sleep 8 & holder2=$!
for _ in $(seq 50); do flock -n "$W/run.lock" true || break; sleep 0.1; done
expect "record into a run being recorded" 2 "in use by ispm record, process 4343" \
  "$ISPM" record "$W/tiny.json" -o "$W/run" --force --quiet
kill $holder $holder2 2> /dev/null; wait 2> /dev/null
[ -e "$W/run/manifest.json" ] || fail "the locked run was touched"

# ---- silent or misleading
golden gtfifo; rm "$W/gtfifo/tolerances.json"; mkfifo "$W/gtfifo/tolerances.json"
expect "tolerances.json is a FIFO" 4 "tolerances.json: is a FIFO" \
  "$ISPM" replay "$W/run" --golden "$W/gtfifo" --report "$W/rep"
golden gtdang; rm "$W/gtdang/tolerances.json"; ln -s "$W/nothing.json" "$W/gtdang/tolerances.json"
expect "tolerances.json is a dangling link" 4 "tolerances.json: is a symbolic link" \
  "$ISPM" replay "$W/run" --golden "$W/gtdang" --report "$W/rep"
golden gtpct; echo '{"default": {"failpercent": 1000}}' > "$W/gtpct/tolerances.json"
expect "failpercent 1000" 4 "\"failpercent\" is 1000, a percentage" \
  "$ISPM" replay "$W/run" --golden "$W/gtpct" --report "$W/rep"
golden gtglob; echo '{"buffers": [{"match": "final.[display", "fail": 1}]}' > "$W/gtglob/tolerances.json"
expect "a rule's glob with an open [" 4 "has a '[' without its ']'" \
  "$ISPM" replay "$W/run" --golden "$W/gtglob" --report "$W/rep"
printf '{"asset": {"version": "2.0"}, "accessors": [{"count": 24, "componentType": 5126, "type": "VEC3",
 "sparse": {"count": 2147483648, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}}}]}\n' > "$W/ext/sparse.gltf"
seq_with "$W/ext/sparse.json" "$W/ext/sparse.gltf"
expect "glTF sparse.count 2^31" 2 "accessors[0].sparse.count 2147483648 is not an integer in 1..24" \
  "$ISPM" record "$W/ext/sparse.json" -o "$W/r" --quiet
expect "lineage --pixel 4294967376,80" 2 "--pixel: '4294967376,80'" \
  "$ISPM" lineage "$W/run" --frame 0 --pixel 4294967376,80
run_copy rdeep; python3 -c "
import sys; open(sys.argv[1], 'w').write('{\"frames\": ' + '[' * 300 + ']' * 300 + '}')" "$W/rdeep/manifest.json"
expect "manifest nested 300 deep" 4 "nested deeper than 256 levels" \
  "$ISPM" replay "$W/rdeep" --golden "$W/gold" --report "$W/rep"
: > "$W/notdir" # a report that cannot be written is not an unreadable input (root ignores chmod)
expect "replay whose report cannot be written" 5 "notdir/rep: cannot create folder" \
  "$ISPM" replay "$W/run" --golden "$W/gold" --report "$W/notdir/rep"
rm -rf "$W/shardT"; cp -r "$W/shardA" "$W/shardT"
python3 - "$W/shardT/frames/000000.exr" << 'EOF'
import sys
# One byte of the last chunk changed: the file still decodes, to other pixels.
b = bytearray(open(sys.argv[1], 'rb').read()); b[-20] ^= 0x01; open(sys.argv[1], 'wb').write(b)
EOF
expect "merge of a shard whose pixels do not match its digests" 2 "shardT/frames/000000.exr" \
  "$ISPM" merge "$W/shardT" "$W/shardB" -o "$W/merged2"
[ ! -e "$W/merged2/manifest.json" ] || fail "a merged run was written from a tampered shard"

echo "e2e_hostile: $CASES cases ok"
