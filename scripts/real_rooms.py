#!/usr/bin/env python3
"""Real rooms as a person would judge their maps, one row per fuse run (scripts/real_rooms.sh).

  scripts/real_rooms.py NAME=RUN/objects.json ...

Per run: the objects; those that stand `on` nothing, by class; the suspected duplicate pairs (one
class, boxes that interpenetrate); the widest object of each class: the larger horizontal side of
its upright box (objects.json `obb`, one axis along `up_in_world`), in metres.
"""
import collections
import json
import math
import sys


def horizontal_width(obj, up):
    rot = obj["obb"]["rotation"]  # row-major, columns are the box's axes
    half = obj["obb"]["half_extent"]
    width = 0.0
    for i in range(3):
        axis = [rot[0 * 3 + i], rot[1 * 3 + i], rot[2 * 3 + i]]
        along_up = abs(sum(a * u for a, u in zip(axis, up)))
        # The full extent of the box's side i seen from above.
        width = max(width, 2.0 * half[i] * math.sqrt(max(0.0, 1.0 - along_up * along_up)))
    return width


def summary(path):
    with open(path) as f:
        doc = json.load(f)
    up = doc.get("up_in_world", [0.0, 0.0, 1.0])
    objects = doc["objects"]
    on_nothing = collections.Counter()
    widest = {}
    duplicates = set()
    for o in objects:
        r = o.get("relations", {})
        if r.get("on") is None:
            on_nothing[o["class"]] += 1
        for d in r.get("suspected_duplicates", []):
            duplicates.add(tuple(sorted((o["id"], d["id"]))))
        w = horizontal_width(o, up)
        if w > widest.get(o["class"], 0.0):
            widest[o["class"]] = w
    return len(objects), sum(on_nothing.values()), on_nothing, len(duplicates), widest


def main(args):
    if not args:
        print(__doc__, file=sys.stderr)
        return 2
    print("| run | objects | on nothing | on nothing, by class | duplicate pairs | widest per class (m) |")
    print("|---|---|---|---|---|---|")
    for arg in args:
        name, path = arg.split("=", 1)
        n, nothing, by_class, dup, widest = summary(path)
        classes = ", ".join(f"{c} {k}" for c, k in sorted(by_class.items())) or "-"
        wide = ", ".join(f"{c} {w:.2f}" for c, w in sorted(widest.items())) or "-"
        print(f"| {name} | {n} | {nothing} | {classes} | {dup} | {wide} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
