#!/usr/bin/env python3
"""The `near` relations of fuse runs per class pair, as a Markdown table (docs/scene.md).

  scripts/near_counts.py NAME=RUN/objects.json ...

One column per run: how many pairs of objects of classes A and B are `near` each other (each pair
once, A <= B by name), the pairs in all, and the objects near a surface of each label
(relations.near_surfaces; "-" for a run written before fuse wrote them).
"""
import collections
import json
import sys


def counts(path):
    with open(path) as f:
        doc = json.load(f)
    objects = doc["objects"]
    cls = {o["id"]: o["class"] for o in objects}
    label = {s["id"]: s["label"] for s in doc.get("surfaces", [])}
    pairs = collections.Counter()
    seen = set()
    surfaces = collections.Counter()
    has_surfaces = False
    for o in objects:
        r = o.get("relations", {})
        for n in r.get("near", []):
            key = tuple(sorted((o["id"], n["id"])))
            if key in seen:
                continue
            seen.add(key)
            pairs[tuple(sorted((o["class"], cls.get(n["id"], "?"))))] += 1
        if "near_surfaces" in r:
            has_surfaces = True
            for n in r["near_surfaces"]:
                surfaces[f"(surface) {label.get(n['id'], '?')}"] += 1
    return pairs, (surfaces if has_surfaces else None), len(seen), len(objects)


def main(args):
    runs = [a.split("=", 1) for a in args]
    results = [(name, counts(path)) for name, path in runs]
    keys = sorted(set(k for _, (p, _, _, _) in results for k in p))
    print("| A near B | " + " | ".join(name for name, _ in results) + " |")
    print("|---|" + "---|" * len(results))
    for k in keys:
        print(f"| {k[0]} near {k[1]} | " + " | ".join(str(p.get(k, 0)) for _, (p, _, _, _) in results) + " |")
    print("| **pairs near** | " + " | ".join(str(n) for _, (_, _, n, _) in results) + " |")
    labels = sorted(set(k for _, (_, s, _, _) in results if s for k in s))
    for k in labels:
        print(f"| objects near a {k} | " +
              " | ".join("-" if s is None else str(s.get(k, 0)) for _, (_, s, _, _) in results) + " |")
    print("| objects | " + " | ".join(str(n) for _, (_, _, _, n) in results) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
