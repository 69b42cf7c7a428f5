#!/usr/bin/env python3
"""The `on` relations of fuse runs per class pair, as a Markdown table (docs/scene.md).

  scripts/relation_counts.py NAME=RUN/objects.json ...

One column per run: how many objects of class A stand `on` B (B an object's class, or a surface's
label: floor, table, seat, surface), how many stand on nothing, how many stand on an object of their
own class, and the suspected duplicates (pairs of one class whose boxes interpenetrate; runs written
before objects.json had them show "-").
"""
import collections
import json
import sys


def counts(path):
    with open(path) as f:
        doc = json.load(f)
    objects = doc["objects"]
    cls = {o["id"]: o["class"] for o in objects}
    pairs = collections.Counter()
    same = 0
    duplicates = set()
    has_duplicates = False
    for o in objects:
        r = o.get("relations", {})
        on = r.get("on")
        if on is None:
            pairs[(o["class"], "(nothing)")] += 1
        else:
            target = cls.get(on["id"], "?") if on["kind"] == "object" else on["label"]
            pairs[(o["class"], target)] += 1
            if on["kind"] == "object" and target == o["class"]:
                same += 1
        if "suspected_duplicates" in r:
            has_duplicates = True
            for d in r["suspected_duplicates"]:
                duplicates.add(tuple(sorted((o["id"], d["id"]))))
    return pairs, same, (len(duplicates) if has_duplicates else None), len(objects)


def main(args):
    runs = [a.split("=", 1) for a in args]
    results = [(name, counts(path)) for name, path in runs]
    keys = sorted(set(k for _, (p, _, _, _) in results for k in p))
    print("| A on B | " + " | ".join(name for name, _ in results) + " |")
    print("|---|" + "---|" * len(results))
    for k in keys:
        print(f"| {k[0]} on {k[1]} | " + " | ".join(str(p.get(k, 0)) for _, (p, _, _, _) in results) + " |")
    print("| **on an object of its own class** | " +
          " | ".join(str(s) for _, (_, s, _, _) in results) + " |")
    print("| **suspected duplicate pairs** | " +
          " | ".join("-" if d is None else str(d) for _, (_, _, d, _) in results) + " |")
    print("| objects | " + " | ".join(str(n) for _, (_, _, _, n) in results) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
