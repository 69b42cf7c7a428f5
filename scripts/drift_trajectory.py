#!/usr/bin/env python3
"""Add a seeded, SLAM-like drift to a TUM trajectory (python3 standard library only).

    scripts/drift_trajectory.py IN.txt OUT.txt [--seed 1] [--drift 0.03] [--yaw-deg-per-m 2.0]

The drifted pose is est_i = D_i * gt_i with D_0 = identity (world frame, as objmap synth does):
  - translation drift: a direction fixed by the seed (plus a random walk of the same size),
    growing linearly with the path length travelled, so that the end position is off by
    `drift` x path length;
  - yaw drift: a rotation about the vertical axis (z of the first camera's world) through the
    first position, growing at a rate of `yaw-deg-per-m` (sign from the seed) per metre travelled.
Same input, seed and options: byte-identical output. Used for the real-image test of
`objmap correct` on fr3_cabinet_58kf (docs/benchmarks.md, "Pose correction (Table 7)").
"""
import argparse
import math
import random

from tum import fail, read_trajectory


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def rotate_z(angle, v):
    c, s = math.cos(angle), math.sin(angle)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1], v[2])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("input")
    parser.add_argument("output")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--drift", type=float, default=0.03,
                        help="end position error as a share of the path length")
    parser.add_argument("--yaw-deg-per-m", type=float, default=2.0,
                        help="yaw drift rate, degrees per metre travelled")
    args = parser.parse_args()

    rows = read_trajectory(args.input)
    if not rows:
        fail(args.input, "no pose; expected lines timestamp tx ty tz qx qy qz qw")

    rng = random.Random(args.seed)
    theta = rng.uniform(0.0, 2.0 * math.pi)
    phi = rng.uniform(-0.3, 0.3)
    direction = (math.cos(theta) * math.cos(phi), math.sin(theta) * math.cos(phi), math.sin(phi))
    yaw_sign = 1.0 if rng.random() < 0.5 else -1.0
    origin = rows[0][1:4]
    travelled = 0.0
    walk = [0.0, 0.0, 0.0]
    previous = rows[0][1:4]
    out = ["# drifted copy of %s: seed %d, drift %g of the path, yaw %g deg/m"
           % (args.input, args.seed, args.drift, args.yaw_deg_per_m),
           "# timestamp tx ty tz qx qy qz qw"]
    for row in rows:
        t, p, q = row[0], row[1:4], row[4:8]
        step = math.dist(p, previous)
        travelled += step
        previous = p
        for k in range(3):
            walk[k] += rng.gauss(0.0, 1.0) * args.drift * step
        offset = [args.drift * travelled * direction[k] * 0.5 + 0.5 * walk[k] for k in range(3)]
        yaw = yaw_sign * math.radians(args.yaw_deg_per_m) * travelled
        rel = [p[k] - origin[k] for k in range(3)]
        rotated = rotate_z(yaw, rel)
        position = [origin[k] + rotated[k] + offset[k] for k in range(3)]
        dq = (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))
        qn = quat_mul(dq, q)
        norm = math.sqrt(sum(x * x for x in qn))
        qn = [x / norm for x in qn]
        if qn[3] < 0:
            qn = [-x for x in qn]
        out.append("%.6f %.6f %.6f %.6f %.8f %.8f %.8f %.8f" % (t, *position, *qn))
    with open(args.output, "w") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
