#!/usr/bin/env python3
"""A perfect scene map in the first camera's frame from objmap synth's ground truth (stdlib only).

    scripts/perfect_scene_map.py S OUT.json

Writes the objects.json that a flawless `objmap fuse --trajectory S/estimated_slam_frame.txt` would
write: every true object, surface and up vector of S/objects_gt.json moved by T_0^-1 (T_0: the first
pose of S/groundtruth.txt, the origin of estimated_slam_frame.txt), the up as R_0^T up, seats
labelled "surface", every object's "on" as the ground truth's (same ids). `objmap eval scene --run
OUT.json --gt S/objects_gt.json --gt-trajectory S/groundtruth.txt --trajectory
S/estimated_slam_frame.txt` then measures what the alignment alone costs (docs/cli.md).
"""
import json
import sys

from tum import fail, quat_to_matrix, read_trajectory


def main():
    if len(sys.argv) != 3:
        fail("usage", "expected: perfect_scene_map.py SEQUENCE_DIR OUT.json")
    seq, out = sys.argv[1], sys.argv[2]
    first = read_trajectory(seq + "/groundtruth.txt")[0]
    r0, t0 = quat_to_matrix(*first[4:8]), first[1:4]

    def to_slam(p):  # R_0^T (p - t_0)
        d = [p[i] - t0[i] for i in range(3)]
        return [sum(r0[k][c] * d[k] for k in range(3)) for c in range(3)]

    def rotate(m):  # R_0^T M for a row-major 3x3
        return [sum(r0[k][r] * m[3 * k + c] for k in range(3)) for r in range(3) for c in range(3)]

    try:
        with open(seq + "/objects_gt.json") as f:
            gt = json.load(f)
    except (OSError, ValueError) as e:
        fail(seq + "/objects_gt.json", "cannot read (%s)" % e)
    up = [r0[2][c] for c in range(3)]  # R_0^T (0, 0, 1)
    surfaces = []
    for s in gt["surfaces"]:
        center = to_slam(s["center"])
        surfaces.append({"id": s["id"], "label": "surface" if s["label"] == "seat" else s["label"],
                         "height_m": sum(up[i] * center[i] for i in range(3)), "center": center,
                         "outline": [to_slam(p) for p in s["outline"]]})
    objects = []
    for o in gt["objects"]:
        c = to_slam(o["centroid"])
        on = None if o["on"] is None else dict(o["on"], gap_m=0.0)
        objects.append({"id": o["id"], "class": o["class"], "score": 1.0, "centroid": c,
                        "position": c, "aabb": {"min": c, "max": c},
                        "obb": {"center": to_slam(o["obb"]["center"]),
                                "rotation": rotate(o["obb"]["rotation"]),
                                "half_extent": o["obb"]["half_extent"]},
                        "points": {"outlier_filtered": 0}, "observation_count": 0, "ply": "",
                        "relations": {"on": on, "near": [], "above": [], "under": []}})
    gravity = [r0[r][c] for r in range(3) for c in range(3)]  # R_0: takes that up to +z
    with open(out, "w") as f:
        json.dump({"up_in_world": up, "gravity_from_world": gravity, "surfaces": surfaces,
                   "objects": objects}, f, indent=1)


if __name__ == "__main__":
    main()
