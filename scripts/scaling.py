#!/usr/bin/env python3
"""Links against elements on two scene families (issue 35), with `antiradiance info --json`.

  rooms:  the bundled Cornell box repeated 1, 2, 4, 8 times side by side (one scene);
  sphere: an icosphere of 1,280 / 5,120 / 20,480 / 81,920 triangles in a closed room.

Prints one row per scene (triangles, elements, links, linking ms) and the exponent b of
links ~ elements^b fitted over the rooms (least squares in log-log), and for the sphere how
elements and links move as its triangles grow 64 times. Usage:

    cargo build --release && python3 scripts/scaling.py [--max-links N]
"""
import json
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(ROOT, "target", "release", "antiradiance")


def info(toml, extra):
    out = subprocess.run([BIN, "info", "--json", toml] + extra, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)


def rooms(tmp, k):
    box = os.path.join(ROOT, "scenes", "cornell-box", "CornellBox-Original.obj")
    lines = ["[camera]", "eye = [0.0, 1.0, 3.9]", "target = [0.0, 1.0, 0.0]",
             "up = [0.0, 1.0, 0.0]", "fov_y_deg = 39.3", "width = 64", "height = 64",
             "[solver]", "bins = 128", "element_size = 0.25", "oracle = 1.0"]
    for i in range(k):
        lines += ["[[object]]", f'mesh = "{box}"', f"translate = [{2.2 * i}, 0.0, 0.0]"]
    path = os.path.join(tmp, f"rooms-{k}.toml")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return path


def icosphere(level):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        mid = {}

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = [(v[a][i] + v[b][i]) / 2 for i in range(3)]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(x / n for x in p))
                mid[key] = len(v) - 1
            return mid[key]
        f = [g for (a, b, c) in f for g in
             ((a, m(a, b), m(c, a)), (b, m(b, c), m(a, b)), (c, m(c, a), m(b, c)),
              (m(a, b), m(b, c), m(c, a)))]
    return v, f


def sphere(tmp, level):
    v, f = icosphere(level)
    obj = os.path.join(tmp, f"sphere-{level}.obj")
    with open(obj, "w") as out:
        for p in v:
            out.write("v %.9f %.9f %.9f\n" % (p[0] * 0.5, p[1] * 0.5 + 0.6, p[2] * 0.5))
        for a, b, c in f:
            out.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))
    room = os.path.join(ROOT, "scenes", "dragon-room", "room.obj")
    path = os.path.join(tmp, f"sphere-{level}.toml")
    with open(path, "w") as out:
        out.write("\n".join([
            "[camera]", "eye = [0.0, 1.15, 1.45]", "target = [0.0, 0.45, 0.0]",
            "up = [0.0, 1.0, 0.0]", "fov_y_deg = 62.0", "width = 64", "height = 64",
            "[solver]", "bins = 128", "element_size = 0.25", "oracle = 1.0",
            "[[object]]", f'mesh = "{room}"', "[[object]]", f'mesh = "{obj}"']) + "\n")
    return path, len(f)


def fit(xs, ys):
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)


def main():
    extra = sys.argv[1:]
    with tempfile.TemporaryDirectory() as tmp:
        print("family  scene        triangles  elements     links  linking_ms")
        e, l = [], []
        for k in (1, 2, 4, 8):
            d = info(rooms(tmp, k), extra)
            e.append(d["elements"])
            l.append(d["links"])
            print(f"rooms   {k} room(s)   {d['triangles']:>10} {d['elements']:>9} "
                  f"{d['links']:>9} {d['linking_ms']:>11.0f}")
        print(f"rooms: links ~ elements^{fit(e, l):.2f}")
        rows = []
        for level in (3, 4, 5, 6):
            path, tris = sphere(tmp, level)
            d = info(path, extra)
            rows.append(d)
            print(f"sphere  level {level}      {d['triangles']:>10} {d['elements']:>9} "
                  f"{d['links']:>9} {d['linking_ms']:>11.0f}")
        t = [d["triangles"] for d in rows]
        print(f"sphere: triangles x{t[-1] / t[0]:.0f}, elements x"
              f"{rows[-1]['elements'] / rows[0]['elements']:.2f}, links x"
              f"{rows[-1]['links'] / rows[0]['links']:.2f}")


if __name__ == "__main__":
    main()
