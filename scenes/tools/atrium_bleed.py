#!/usr/bin/env python3
"""Colour bleeding in a recorded atrium run: the indirect light on the floor in front of each
curtain (issue 17 item 8's measure).

For each curtain (red, green, blue: make_atrium.py's CURTAINS) it averages `indirect.radiance`
over the floor pixels (gbuffer.position y < 1 cm, gbuffer.normal y > 0.9) whose point lies within
the curtain's bay (x between its columns' faces) and 0.2 to 1.2 m in front of it (toward the
court), and prints the mean R, G, B, R/G and B/G and the pixel count. Buffers are read with
`ispm export` and oiiotool --dumpdata (openimageio-tools), so only the stdlib is needed.

With --check it exits 1 unless, in front of the red curtain, R > G, and R/G there is over 1.5
times R/G in front of the green curtain: the two curtains tint the floor by their own colours (the
warm sandstone around them is the same for both bays; with both curtains grey, atrium-ci's
frame 0 gives 1.33 and 1.40, a ratio of 0.95, and with their colours 2.33 and 1.02). Exit 2 on bad arguments or unreadable runs.
With --reference REF (an `ispm reference` run of the same sequence) the same pixels of its
`reference.indirect` are averaged too (positions and normals from RUN's G-buffer).
usage: atrium_bleed.py ISPM RUN [--frame F] [--reference REF] [--check]"""
import os, subprocess, sys, tempfile

ZC, HALF_T = 2.5, 0.15
CURTAINS = [("red", -3.0), ("green", 1.0), ("blue", 3.0)]   # make_atrium.py: bay's left column
COL_R = 0.22


def die(msg, code=2):
    print("atrium_bleed.py: " + msg, file=sys.stderr)
    sys.exit(code)


def read(ispm, run, frame, buf, tmp):
    out = os.path.join(tmp, buf + ".exr")
    r = subprocess.run([ispm, "export", run, "--frame", str(frame), "--buffer", buf, "-o", out],
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode:
        die("%s: ispm export %s exited %d: %s" % (run, buf, r.returncode, r.stderr.strip()))
    r = subprocess.run(["oiiotool", "--dumpdata", out], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode:
        die("%s: oiiotool --dumpdata exited %d" % (out, r.returncode))
    px = {}
    for line in r.stdout.splitlines():
        line = line.strip()
        if line.startswith("Pixel ("):
            head, vals = line.split(":", 1)
            x, y = head[len("Pixel ("):-1].split(",")
            px[(int(x), int(y))] = [float(v) for v in vals.split()]
    if not px:
        die("%s: no pixels in %s" % (run, buf))
    return px


def report(label, ind, pos, nrm):
    """Mean indirect R, G, B on the floor in front of each curtain, printed; {name: [r, g, b]}."""
    res = {}
    for name, xa in CURTAINS:
        s, n = [0.0, 0.0, 0.0], 0
        for k, p in pos.items():
            if p[1] < 0.01 and nrm[k][1] > 0.9 and xa + COL_R < p[0] < xa + 2.0 - COL_R and \
               ZC - HALF_T - 1.2 < p[2] < ZC - HALF_T - 0.2:
                for c in range(3):
                    s[c] += ind[k][c]
                n += 1
        if n == 0:
            die("no floor pixel in front of the %s curtain" % name, 1)
        m = [v / n for v in s]
        res[name] = m
        print("%s%s curtain: floor indirect R %.4f G %.4f B %.4f  R/G %.3f  B/G %.3f  (%d pixels)" %
              (label, name, m[0], m[1], m[2], m[0] / m[1], m[2] / m[1], n))
    return res


def main(argv):
    args = [a for a in argv if not a.startswith("--")]
    check = "--check" in argv
    frame, ref = 0, None
    for opt in ("--frame", "--reference"):
        if opt in argv:
            i = argv.index(opt)
            if i + 1 >= len(argv) or argv[i + 1].startswith("--"):
                die(opt + " needs a value")
            args.remove(argv[i + 1])
            if opt == "--frame":
                if not argv[i + 1].isdigit():
                    die("--frame needs a frame index")
                frame = int(argv[i + 1])
            else:
                ref = argv[i + 1]
    if len(args) != 2:
        die("usage: atrium_bleed.py ISPM RUN [--frame F] [--reference REF] [--check]")
    ispm, run = args
    with tempfile.TemporaryDirectory(prefix="atrium-bleed-") as tmp:
        ind = read(ispm, run, frame, "indirect.radiance", tmp)
        pos = read(ispm, run, frame, "gbuffer.position", tmp)
        nrm = read(ispm, run, frame, "gbuffer.normal", tmp)
        refind = read(ispm, ref, frame, "reference.indirect", tmp) if ref else None
    res = report("", ind, pos, nrm)
    if refind:
        report("reference: ", refind, pos, nrm)
    if check:
        r, g = res["red"], res["green"]
        if not (r[0] > r[1] and r[0] / r[1] > 1.5 * (g[0] / g[1])):
            die("%s frame %d: no colour bleeding from the curtains (red R/G %.3f, green R/G %.3f)" %
                (run, frame, r[0] / r[1], g[0] / g[1]), 1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
