#!/usr/bin/env python3
"""The tables of `make ablation` (scripts/ablation.sh) from its outputs (standard library only).

  ablation_tables.py render --ablation out/ablation [--doc docs/benchmarks.md]
                            [--fusion-doc docs/fusion.md] [--objmap BIN] [--command ...]
                            [--seconds N]
      reads out/ablation/{features.txt, columns.txt, ablation/<row>/<column>/,
      sweep/<set>/seed<N>/<cell>/}
      and writes out/ablation/tables.md; the ablation tables replace the part of --doc between
      <!-- ablation:begin --> and <!-- ablation:end -->, the sweep the part of --fusion-doc between
      <!-- sweep:begin --> and <!-- sweep:end --> (each appended at the end of its file when it
      has no markers). The rest of both files is left as it is.

A cell against the true objects reads "13/12 d1 · 2.1 cm": 13 objects mapped for 12 true ones, one
duplicate (a map object that is not matched but lies within the gate, 0.3 m, of a true object of its
class that another map object matches), mean position error of the matched objects (eval objects'
position_distance_m: the map object's `position`, the centroid under --method paper (eq 16), to
the true object's box centre); "· 1 missed" follows when a true object has no match. A cell of the
estimate: mean centroid error of the map fused with the estimate against the map fused with
groundtruth.txt (Tables 4-5, objects matched one-to-one by class) and the object points kept
(run.json, outlier-filtered).
"""
import argparse
import datetime
import glob
import os
import re
import sys

from bench_tables import (add_render_arguments, load_json, machine, md_table, read_meta,
                          write_section)

MARKERS = {
    "ablation": ("<!-- ablation:begin -->", "<!-- ablation:end -->"),
    "sweep": ("<!-- sweep:begin -->", "<!-- sweep:end -->"),
}
GATE_M = 0.3  # eval objects' default gate
# Column groups of the two table pairs (names of scripts/ablation.sh's COLUMNS).
ASSOCIATION = ["paper", "objmap", "iou", "tolerance", "gate_radius", "distance_gate", "weights",
               "one_per_frame", "best_first", "final_merge", "class_confusions", "confirmation"]
DEFAULTS = {"wid": "0.3", "wd": "0.2", "wm": "0.5", "k": "0.4"}  # objmap's eq 22 defaults


def read_columns(path):
    cols = []
    try:
        with open(path) as f:
            for line in f:
                if line.strip():
                    name, label, args = line.rstrip("\n").split("|", 2)
                    cols.append({"name": name, "label": label, "args": args})
    except OSError:
        pass
    return cols


def same_class(a, b):
    norm = lambda s: re.sub(r"[\s_]+", "", s.lower())
    return norm(a) == norm(b)


def truth_summary(ev, objects):
    """Counts, duplicates and missed of eval objects --gt-objects (one-to-one by class within the
    gate, on the point means), and the position error of each matched object (position_distance_m:
    its `position` to the true object's box centre; the paper's `position` is its centroid)."""
    if not ev:
        return None
    counts = next((c for c in ev["counts"] if c["class"] == "overall"), None)
    if not counts:
        return None
    matches = ev.get("matches", [])
    # The true objects' centroids from the matches (error = map centroid - true centroid).
    by_id = {o["id"]: o for o in (objects or {}).get("objects", [])}
    truth = []
    dists = []
    for m in matches:
        o = by_id.get(m["map_id"])
        if not o:
            continue
        truth.append((m["class"], [c - e for c, e in zip(o["centroid"], m["error_xyz_m"])]))
        if "position_distance_m" in m:
            dists.append(m["position_distance_m"])
    dup = 0
    for mid in ev.get("unmatched_map_ids", []):
        o = by_id.get(mid)
        if not o:
            continue
        if any(same_class(o["class"], cls) and
               sum((a - b) ** 2 for a, b in zip(o["centroid"], c)) ** 0.5 <= GATE_M
               for cls, c in truth):
            dup += 1
    return {"mapped": counts["mapped"], "truth": counts["reference"], "dup": dup,
            "matched": len(matches), "missed": counts["reference"] - len(matches),
            "dists": dists, "mean": sum(dists) / len(dists) if dists else None}


def cm(v):
    return "—" if v is None else "%.1f cm" % (100.0 * v)


def truth_cell(s, run):
    if s:
        cell = "%d/%d d%d · %s" % (s["mapped"], s["truth"], s["dup"], cm(s["mean"]))
        if s["missed"] > 0:
            cell += " · %d missed" % s["missed"]
        return cell
    counts = (load_json(os.path.join(run, "run.json")) or {}).get("counts") if run else None
    if counts:  # no true objects: confirmed of all objects
        return "%d of %d" % (counts.get("objects_confirmed", 0),
                             counts.get("objects_before_confirmation", 0))
    return "failed"


def kilo(n):
    if n is None:
        return "—"
    return "%.1fk" % (n / 1000.0) if n >= 1000 else "%d" % n


def est_cell(ev, run_json):
    parts = []
    e = next((c for c in (ev or {}).get("centroid_error", []) if c["class"] == "overall"), None)
    if e and e["matched"]:
        parts.append("%s (%d/%d)" % (cm(e["distance_m"]["mean"]), e["matched"], e["reference"]))
    elif ev:
        parts.append("0 matched")
    else:
        parts.append("—")
    pts = ((run_json or {}).get("points") or {}).get("objects_outlier_filtered")
    parts.append(kilo(pts))
    return " · ".join(parts)


def flat(d, prefix=""):
    out = {}
    for k, v in (d or {}).items():
        if isinstance(v, dict):
            out.update(flat(v, prefix + k + "."))
        else:
            out[prefix + k] = v
    return out


def coverage(rows, cols):
    """Options where --method paper differs from objmap, and the columns that set each."""
    for row in rows:
        opts = {c["name"]: flat((load_json(os.path.join(row, c["name"], "run_gt", "run.json"))
                                 or {}).get("options")) for c in cols}
        if not opts.get("paper") or not opts.get("objmap"):
            continue
        base = opts["objmap"]
        diff = sorted(k for k in base if k != "method" and opts["paper"].get(k) != base[k])
        covered = {}
        for c in cols:
            if c["name"] in ("paper", "objmap") or not opts.get(c["name"]):
                continue
            for k in diff:
                if opts[c["name"]].get(k) != base[k] and opts[c["name"]].get(k) == opts["paper"][k]:
                    covered.setdefault(k, []).append(c["name"])
        missing = [k for k in diff if k not in covered]
        return diff, missing
    return [], []


def ablation_section(root, cols):
    rows = sorted(d for d in glob.glob(os.path.join(root, "ablation", "*")) if os.path.isdir(d))
    synth = [r for r in rows if os.path.basename(r).startswith("synth_")]
    rows = synth + [r for r in rows if r not in synth]
    names = [c["name"] for c in cols]
    groups = [[n for n in names if n in ASSOCIATION],
              ["objmap"] + [n for n in names if n not in ASSOCIATION]]
    label = {c["name"]: c["label"] for c in cols}
    cells_truth, cells_est, total = {}, {}, {}
    for row in rows:
        r = os.path.basename(row)
        for n in names:
            d = os.path.join(row, n)
            run = os.path.join(d, "run_gt")
            if not os.path.isdir(d):  # not run (ABLATION_COLUMNS, or cut short)
                cells_truth[r, n] = cells_est[r, n] = "—"
                continue
            s = truth_summary(load_json(os.path.join(d, "vs_truth.json")),
                              load_json(os.path.join(run, "objects.json")))
            cells_truth[r, n] = truth_cell(s, run if os.path.isdir(run) else None)
            cells_est[r, n] = est_cell(load_json(os.path.join(d, "est_vs_gtmap.json")),
                                       load_json(os.path.join(run, "run.json")))
            if s:
                t = total.setdefault(n, {"err": 0, "dup": 0, "missed": 0, "dists": [], "rows": 0})
                t["err"] += abs(s["mapped"] - s["truth"])
                t["dup"] += s["dup"]
                t["missed"] += s["missed"]
                t["dists"] += s["dists"]
                t["rows"] += 1
    out = []
    titles = ["association, confirmation (objmap's changes to §3.2)",
              "filters and masks (objmap's changes to §3.1 and §3.3)"]
    for title, group in zip(titles, groups):
        out += ["#### Objects vs the true objects: %s" % title, ""]
        body = [[os.path.basename(r)] + [cells_truth[os.path.basename(r), n] for n in group]
                for r in rows]
        tot = ["**sum of the rows with true objects**"]
        for n in group:
            t = total.get(n)
            tot.append("—" if not t else "err %d · d%d · %d missed · %s" % (
                t["err"], t["dup"], t["missed"],
                cm(sum(t["dists"]) / len(t["dists"]) if t["dists"] else None)))
        out += [md_table(["sequence"] + [label[n] for n in group], body + [tot]), ""]
    for title, group in zip(titles, groups):
        out += ["#### Estimate map vs ground-truth map (Tables 4–5) · object points kept: %s"
                % title, ""]
        body = [[os.path.basename(r)] + [cells_est[os.path.basename(r), n] for n in group]
                for r in rows]
        out += [md_table(["sequence"] + [label[n] for n in group], body), ""]
    diff, missing = coverage(rows, cols)
    if diff:
        out.append("Options that `--method paper` sets differently from objmap's defaults "
                   "(run.json `options`): %s. %s" % (
                       ", ".join("`%s`" % k for k in diff),
                       "Each is set to the paper's value by a column of its own (the weights "
                       "`weight_id` and `weight_distance` together)." if not missing else
                       "Not covered by any column: %s." % ", ".join("`%s`" % k for k in missing)))
        out.append("")
    return out


SWEEP_SETS = [  # (name in scripts/ablation.sh's sweep_sets, what the table is titled)
    ("hard", "Scenes that put the weights to the test"),
    ("default", "Scenes at the default orbit and rates"),
]


def sweep_section(root, set_name, title, wm, synth_args):
    cells = {}
    set_dir = os.path.join(root, "sweep", set_name)
    for path in glob.glob(os.path.join(set_dir, "seed*", "*")):
        m = re.match(r"wid([\d.]+)_wd([\d.]+)_wm([\d.]+)_k([\d.]+)$", os.path.basename(path))
        if not m:
            continue
        s = truth_summary(load_json(os.path.join(path, "vs_truth.json")),
                          load_json(os.path.join(path, "run_gt", "objects.json")))
        key = m.groups()
        c = cells.setdefault(key, {"mapped": 0, "truth": 0, "dup": 0, "missed": 0, "dists": [],
                                   "seeds": 0, "exact": 0, "failed": 0})
        if not s:
            c["failed"] += 1
            continue
        c["seeds"] += 1
        c["exact"] += s["mapped"] == s["truth"] and s["missed"] == 0
        for k in ("mapped", "truth", "dup", "missed"):
            c[k] += s[k]
        c["dists"] += s["dists"]
    if not cells:
        return []
    seeds = sorted({os.path.basename(p)[4:]
                    for p in glob.glob(os.path.join(set_dir, "seed*"))}, key=int)
    ks = sorted({k[3] for k in cells}, key=float)
    pairs = sorted({(k[0], k[1]) for k in cells}, key=lambda p: (float(p[0]), float(p[1])))
    body = []
    exact_cells = []
    default_key = (DEFAULTS["wid"], DEFAULTS["wd"], DEFAULTS["wm"], DEFAULTS["k"])
    for wid, wd in pairs:
        row = ["%s, %s" % (wid, wd)]
        for k in ks:
            c = cells.get((wid, wd, wm, k))
            if not c or not c["seeds"]:
                row.append("—")
                continue
            text = "%d/%d d%d%s · %s · %d/%d exact" % (
                c["mapped"], c["truth"], c["dup"],
                " · %d missed" % c["missed"] if c["missed"] else "",
                cm(sum(c["dists"]) / len(c["dists"]) if c["dists"] else None), c["exact"],
                c["seeds"])
            if c["exact"] == c["seeds"] == len(seeds):
                exact_cells.append((wid, wd, wm, k))
            if (wid, wd, wm, k) == default_key:
                text = "**%s** (default)" % text
            row.append(text)
        body.append(row)
    reading = "Cells that map every seed exactly: %d of %d%s." % (
        len(exact_cells), sum(1 for c in cells.values() if c["seeds"]),
        "; objmap's default is one of them" if default_key in exact_cells
        else "; objmap's default is not one of them")
    return [
        "#### %s: `objmap synth --seed N%s`" % (title, (" " + synth_args) if synth_args else ""),
        "",
        "N = %s, fused with groundtruth.txt; w_m = %s held (P > K is unchanged when the "
        "weights and K are scaled together). A cell sums the seeds: objects mapped / true, "
        "duplicates, missed, the mean position error of all matched objects (`position` to "
        "the true box centre), and the seeds "
        "mapped exactly (every true object matched, no extra object)." % (", ".join(seeds), wm),
        "",
        md_table(["w_id, w_d"] + ["K = %s" % k for k in ks], body),
        "",
        reading,
        "",
    ]


def render(args):
    root = os.path.abspath(args.ablation)
    features = read_meta(os.path.join(root, "features.txt"))
    cols = read_columns(os.path.join(root, "columns.txt"))
    cpu, version, commit = machine(args.objmap)
    date = features.get("date") or datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M UTC")
    took = " in %.0f min" % (args.seconds / 60.0) if args.seconds else ""
    header = ("Generated by `%s` on %s%s; %s%s; machine: %s, load average %s at the start. "
              "JSON of every run and evaluation: `out/ablation/`." % (
                  args.command, date, took, version or "objmap",
                  (" (git " + commit + ")") if commit else "", cpu,
                  features.get("load_start", "?")))
    # A part that did not run (ABLATION_PARTS) leaves its table in the docs as it is.
    ran = glob.glob(os.path.join(root, "ablation", "*", "*", "run_gt"))
    abl = ablation_section(root, cols) if cols and ran else []
    sweep = []
    for name, title in SWEEP_SETS:
        if "sweep_set_" + name in features:
            sweep += sweep_section(root, name, title, features.get("sweep_wm", DEFAULTS["wm"]),
                                   features["sweep_set_" + name])
    tables = []
    if abl:
        b, e = MARKERS["ablation"]
        section = "\n".join([
            b, "### Ablation: the paper, objmap, and objmap with one change reverted "
            "(generated by `make ablation`)", "", header, "",
            "Rows: `objmap synth --seed N` at the default orbit, seed 1 at `--orbit-speed 60`, "
            "seed 5 with `--confusion-rate 0.2 --id-switch-rate 0.2`, and the sequences of DATA "
            "(as `make bench` finds them; short clips with `--keyframes all`). Columns: `fuse "
            "--method paper`, objmap's defaults, and the defaults with one option set as the "
            "paper has it. Every fuse runs with `--dense-stride 4` (the dense map at every 4th "
            "pixel: it gives the up direction, the frame of the positions; docs/benchmarks.md, "
            "How make bench works).",
            "",
            "Objects vs the true objects (fused with groundtruth.txt): `13/12 d1 · 2.1 cm` = 13 "
            "objects mapped for 12 true ones, 1 duplicate (an unmatched map object within 0.3 m "
            "of a true object of its class that another map object matches), mean position error "
            "of the matched objects (`objmap eval objects --gt-objects`: matched one-to-one by "
            "class within 0.3 m on the point means; `position_distance_m`, the object's "
            "`position`, the centroid under `--method paper` (eq 16), to the true object's box "
            "centre: `obb.center` of objects_gt.json, fr3_cabinet's cuboid, the YCB-Video "
            "model origins); `· 1 missed`: a true object without a match. Sequences without true "
            "objects: `17 of 48` = objects confirmed of all objects the fusion made (run.json "
            "`counts`).", "",
        ] + abl + [
            "The sum row: Σ |mapped − true| over the rows, Σ duplicates, Σ missed, and the "
            "mean position error of all matched objects.", "",
            "Estimate cells: `4.7 cm (12/12) · 35.1k` = mean centroid error of the map fused "
            "with the estimate against the map fused with groundtruth.txt (the same column's "
            "options, over the estimate's frames; `eval objects --reference`), matched of the "
            "reference map's objects, and the object points kept by the groundtruth.txt run "
            "(run.json `points.objects_outlier_filtered`).", e])
        tables.append(section)
        if args.doc:
            write_section(args.doc, section, b, e, after_intro=False)
    if sweep:
        b, e = MARKERS["sweep"]
        section = "\n".join([b, header, ""] + sweep + [e])
        tables.append(section)
        if args.fusion_doc:
            write_section(args.fusion_doc, section, b, e, after_intro=False)
    with open(os.path.join(root, "tables.md"), "w") as f:
        f.write("\n\n".join(tables) + "\n")
    print("\n\n".join(tables))
    return 0


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="what", required=True)
    r = sub.add_parser("render", help="write the Markdown tables")
    r.add_argument("--ablation", default="out/ablation")
    r.add_argument("--fusion-doc", default="")
    add_render_arguments(r, "make ablation")
    args = p.parse_args()
    return {"render": render}[args.what](args)


if __name__ == "__main__":
    sys.exit(main())
