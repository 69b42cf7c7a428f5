#!/usr/bin/env python3
"""Object positions of objmap fuse runs on synthetic scenes against the position tolerance.

For each SCENE:RUN pair (a folder of `objmap synth` and an `objmap fuse` run of it with
groundtruth.txt), every map object is matched to a ground-truth object of its class (nearest
`position`, within 0.3 m) and compared with the ground-truth `centroid` (the volume centroid) under
the tolerance max(2 cm, 10% of the object's largest dimension). Several position estimates from
the object's PLY and the cameras that saw it are scored side by side:

  position     objects.json's `position` (objmap's estimate: middle of the points' 1-99% box)
  mean         the mean of the points (objects.json's `centroid`)
  box_xy_mean_z  the 5-95% box in x and y, the mean height
  front_half   the box, moved along the mean horizontal viewing direction so that its centre is
               half the object's width (across the view) behind its front
  circle       a circle fitted to the points in x-y (Kasa), the box height
  box_q01      the middle of the points' 1-99% box
  aabb         the middle of the points' full box (objects.json's `aabb`)

It also prints, per class, how far the ground truth's volume centroid is from its box centre.
With --gt box the estimates are scored against the ground truth's box centre (`obb.center`, what
the real data's references are: fr3_cabinet's cuboid, the YCB-Video model origins) instead.
Pure Python (no numpy):

  python3 scripts/centroid_tolerance.py [--gt centroid|box] S1:R1 S2:R2 ...
"""
import json
import math
import struct
import sys


def read_ply_xyz(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    n = int([l for l in header.split("\n") if l.startswith("element vertex")][0].split()[2])
    stride = 15 if "property uchar red" in header else 12
    return [struct.unpack_from("<3f", data, end + i * stride) for i in range(n)]


def read_positions(path):
    out = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = [float(x) for x in line.split()]
            out[round(v[0], 4)] = v[1:4]
    return out


def percentile(values, q):
    s = sorted(values)
    k = (len(s) - 1) * q
    lo, hi = int(math.floor(k)), int(math.ceil(k))
    return s[lo] + (s[hi] - s[lo]) * (k - lo)


def solve3(a, b):
    """Solves the 3x3 system a x = b (Cramer's rule)."""
    def det(m):
        return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
    d = det(a)
    out = []
    for c in range(3):
        m = [row[:] for row in a]
        for r in range(3):
            m[r][c] = b[r]
        out.append(det(m) / d)
    return out


def estimates(points, cameras, position):
    n = len(points)
    mean = [sum(p[a] for p in points) / n for a in range(3)]
    box = [(percentile([p[a] for p in points], 0.05) + percentile([p[a] for p in points], 0.95)) / 2
           for a in range(3)]
    box01 = [(percentile([p[a] for p in points], 0.01) + percentile([p[a] for p in points], 0.99)) /
             2 for a in range(3)]
    aabb = [(min(p[a] for p in points) + max(p[a] for p in points)) / 2 for a in range(3)]
    # Mean horizontal viewing direction from the cameras to the mean point.
    vx = vy = 0.0
    for c in cameras:
        dx, dy, dz = mean[0] - c[0], mean[1] - c[1], mean[2] - c[2]
        norm = math.sqrt(dx * dx + dy * dy + dz * dz)
        vx += dx / norm
        vy += dy / norm
    h = math.hypot(vx, vy)
    vx, vy = vx / h, vy / h
    along = [p[0] * vx + p[1] * vy for p in points]
    across = [-p[0] * vy + p[1] * vx for p in points]
    width = percentile(across, 0.95) - percentile(across, 0.05)
    shift = max(0.0, percentile(along, 0.05) + width / 2 - (box[0] * vx + box[1] * vy))
    # Circle in x-y: x^2 + y^2 = 2 a x + 2 b y + c, least squares.
    sxx = sum(p[0] * p[0] for p in points)
    sxy = sum(p[0] * p[1] for p in points)
    syy = sum(p[1] * p[1] for p in points)
    sx = sum(p[0] for p in points)
    sy = sum(p[1] for p in points)
    r2 = [p[0] * p[0] + p[1] * p[1] for p in points]
    cx2, cy2, c = solve3([[sxx, sxy, sx], [sxy, syy, sy], [sx, sy, n]],
                         [sum(r * p[0] for r, p in zip(r2, points)),
                          sum(r * p[1] for r, p in zip(r2, points)), sum(r2)])
    return {
        "position": position,
        "mean": mean,
        "box_xy_mean_z": [box[0], box[1], mean[2]],
        "front_half": [box[0] + shift * vx, box[1] + shift * vy, box[2]],
        "circle": [cx2 / 2, cy2 / 2, box[2]],
        "box_q01": box01,
        "aabb": aabb,
    }


def main(pairs, reference="centroid"):
    beyond, total, offsets = {}, 0, {}

    def truth(g):
        return g["centroid"] if reference == "centroid" else g["obb"]["center"]

    for pair in pairs:
        scene, run = pair.split(":")
        gt = json.load(open(scene + "/objects_gt.json"))["objects"]
        cams = read_positions(scene + "/groundtruth.txt")
        for g in gt:
            box_centre = g["obb"]["center"]
            offsets.setdefault(g["class"], math.dist(g["centroid"], box_centre))
        used = set()
        for o in json.load(open(run + "/objects.json"))["objects"]:
            pos = o["position"]
            best = None
            for k, g in enumerate(gt):
                if g["class"] != o["class"] or k in used:
                    continue
                d = math.dist(pos, g["centroid"])
                if d <= 0.3 and (best is None or d < best[0]):
                    best = (d, k)
            if best is None:
                continue
            used.add(best[1])
            g = gt[best[1]]
            tol = max(0.02, 0.2 * max(g["obb"]["half_extent"]))
            points = read_ply_xyz(run + "/" + o["ply"])
            cameras = [cams[round(ob["timestamp"], 4)] for ob in o["observations"]]
            total += 1
            for name, p in estimates(points, cameras, pos).items():
                err = math.dist(p, truth(g))
                if err > tol:
                    beyond.setdefault(name, []).append(
                        "%s:%s %.1f/%.1f cm" % (scene, g["class"], 100 * err, 100 * tol))
    print("objects matched: %d; ground truth: %s" % (
        total, "volume centroid" if reference == "centroid" else "box centre (obb.center)"))
    for name in ("position", "mean", "box_xy_mean_z", "front_half", "circle", "box_q01", "aabb"):
        misses = beyond.get(name, [])
        print("%-14s beyond the tolerance: %d/%d" % (name, len(misses), total))
        for m in misses:
            print("    " + m)
    print("ground truth: volume centroid to box centre, per class [cm]")
    for cls, d in sorted(offsets.items()):
        print("    %-12s %.1f" % (cls, 100 * d))


if __name__ == "__main__":
    args = sys.argv[1:]
    reference = "centroid"
    if len(args) >= 2 and args[0] == "--gt":
        reference = args[1]
        args = args[2:]
    if reference not in ("centroid", "box") or not args:
        sys.exit("usage: centroid_tolerance.py [--gt centroid|box] SCENE:RUN [SCENE:RUN ...]")
    main(args, reference)
