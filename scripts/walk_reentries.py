#!/usr/bin/env python3
"""The walk from run_fuse's options: how often a reader who follows them returns to a file.

Usage: scripts/walk_reentries.py [REPO]   (default: the repository this script is in)

Reads the function definitions of lib/objmap/pipeline/*.cpp (a definition starts at column 0 and
its body ends at the next "}" at column 0). The walk starts at run_fuse and follows, in the order
of the calls in each body, every call of a pipeline function that takes the fuse's options
(a parameter of type FuseOptions, FuseChoices or KeyframeContext, the per-run context that carries
them); each function is read once, depth first, as a reader would open it. The walk is the
sequence of files of the functions read. A re-entry is a step of the walk into a file that the
walk has been in before but has left since. Prints the walk, the re-entries per file and in all;
exits 1 when a file is re-entered more than 5 times (the bar of issue 40). Also prints how many of
run_fuse's own steps lie in other files: the returns to the outline, which a reader keeps open.
"""
import os
import re
import sys

OPTION_TYPES = ("FuseOptions", "FuseChoices", "KeyframeContext")
DEFINITION = re.compile(r"^[A-Za-z_][\w:<>,\s\*&]*?\b([A-Za-z_]\w*)\s*\(")


def definitions(folder):
    """name -> (file, parameter text, body text) of every function defined at column 0."""
    found = {}
    for name in sorted(os.listdir(folder)):
        if not name.endswith(".cpp"):
            continue
        lines = open(os.path.join(folder, name), encoding="utf-8").read().split("\n")
        i = 0
        while i < len(lines):
            m = DEFINITION.match(lines[i])
            if not m or lines[i].startswith(("namespace", "using", "struct", "class", "#", "//")):
                i += 1
                continue
            # The signature runs to the line that ends with "{"; a ";" first: a declaration.
            j = i
            while j < len(lines) and not lines[j].rstrip().endswith("{") and ";" not in lines[j]:
                j += 1
            if j >= len(lines) or ";" in lines[j] and not lines[j].rstrip().endswith("{"):
                i = j + 1
                continue
            signature = "\n".join(lines[i:j + 1])
            k = j + 1
            while k < len(lines) and lines[k] != "}":
                k += 1
            fn = m.group(1)
            if fn not in found:  # the first definition of a name (overloads are rare here)
                found[fn] = (name, signature, "\n".join(lines[j + 1:k]))
            i = k + 1
    return found


def walk(found, start="run_fuse"):
    """The functions read, depth first in call order, from `start`."""
    order, seen = [], set()

    def takes_options(fn):
        return any(t in found[fn][1] for t in OPTION_TYPES)

    def visit(fn):
        seen.add(fn)
        order.append(fn)
        body = found[fn][2]
        calls = sorted((m.start(), m.group(1)) for m in re.finditer(r"\b([A-Za-z_]\w*)\s*\(", body))
        for _, callee in calls:
            if callee in found and callee not in seen and takes_options(callee):
                visit(callee)

    visit(start)
    return order


def main():
    repo = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(
        os.path.abspath(__file__)))
    found = definitions(os.path.join(repo, "lib", "objmap", "pipeline"))
    order = walk(found)
    files = [found[fn][0] for fn in order]
    reentries = {}
    been, previous = set(), None
    for f in files:
        if f != previous and f in been:
            reentries[f] = reentries.get(f, 0) + 1
        been.add(f)
        previous = f
    for fn, f in zip(order, files):
        print(f"  {f:28s} {fn}")
    print("re-entries per file:", reentries if reentries else "none")
    worst = max(reentries.values(), default=0)
    print(f"functions read: {len(order)}, files: {len(been)}, re-entries: "
          f"{sum(reentries.values())} in all, at most {worst} into one file")
    # The outline itself: run_fuse's own steps in other files (the reader comes back to it after
    # each; an outline is read that way, so these are not re-entries).
    steps = [c for _, c in sorted((m.start(), m.group(1)) for m in re.finditer(
        r"\b([A-Za-z_]\w*)\s*\(", found["run_fuse"][2])) if c in order and found[c][0] != files[0]]
    print(f"run_fuse's steps in other files (returns to the outline {files[0]}): {len(steps)}")
    return 1 if worst > 5 else 0


if __name__ == "__main__":
    sys.exit(main())
