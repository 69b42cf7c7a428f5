#!/usr/bin/env python3
"""The tables of `make bench` from its outputs (python3 standard library only).

  bench_tables.py measure --json F -- CMD ARGS...
      runs CMD, writes {"seconds", "cpu_seconds", "peak_rss_mb", "exit_code", "command"} to F
      (peak RSS and CPU of the child process, from getrusage); exits with CMD's exit code.
  bench_tables.py prepare --dataset DIR --gt GT --est EST --out-dir D
      the estimate as the maps of Tables 4-5 need it; prints key=value lines:
      estimate=F   the estimate in the ground truth's world frame: EST itself, or, when EST starts
                   at the identity in its own frame (as SLAM systems write it) and the ground truth
                   does not, D/estimate_aligned.txt: every pose moved by the ground truth's pose at
                   the estimate's first stamp (as if the run had been started there; aligned=1);
      reference=F  D/groundtruth_span.txt, the ground truth cut to the estimate's time span, when
                   the estimate covers fewer frames than the ground truth (empty otherwise): the
                   reference map is then fused over the same frames.
  bench_tables.py render --bench out/bench --doc docs/benchmarks.md [--data DIR] [--objmap BIN]
                         [--command "make bench ..."] [--seconds N]
      reads out/bench/<sequence>/{meta.txt, run_*/run.json, ate_*.json, objects_*.json} and
      out/bench/perf/, writes out/bench/tables.md and replaces the part of --doc between the lines
      <!-- bench:begin --> and <!-- bench:end --> (inserted before the second heading of the file
      when it has no markers). The rest of the file is left as it is.
"""
import argparse
import datetime
import glob
import json
import os
import platform
import re
import resource
import subprocess
import sys
import time

from tum import nearest, quat_to_matrix, read_list, read_trajectory

BEGIN = "<!-- bench:begin -->"
END = "<!-- bench:end -->"

# The seed paper (Sensors 2022, 22, 7576).
PAPER_TABLE7 = {
    "sequences": ["fr3_office", "fr3_teddy", "fr2_desk", "fr1_room", "fr1_desk"],
    "ORB-SLAM2": [0.0121, 0.0225, 0.0095, 0.0474, 0.0163],
    "Ours (paper)": [0.0115, 0.0259, 0.0086, 0.0452, 0.0153],
}
PAPER_TABLE4_FR3_OFFICE = 0.0109  # mean centroid error, ORB-SLAM2 map vs ground-truth map, m
PAPER_TABLE6_REDUCTION = "45.3–61.5%"


# ----------------------------------------------------------------------------------------- measure
def measure(args):
    cmd = args.cmd[1:] if args.cmd and args.cmd[0] == "--" else args.cmd
    if not cmd:
        sys.stderr.write("bench_tables measure: no command after --\n")
        return 2
    t0 = time.perf_counter()
    proc = subprocess.run(cmd)
    seconds = time.perf_counter() - t0
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    result = {
        "command": cmd,
        "exit_code": proc.returncode,
        "seconds": seconds,
        "cpu_seconds": usage.ru_utime + usage.ru_stime,
        "peak_rss_mb": usage.ru_maxrss / 1024.0,
    }
    with open(args.json, "w") as f:
        json.dump(result, f, indent=2)
    return proc.returncode


# ----------------------------------------------------------------------------------------- prepare
def matrix_to_quat(m):
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = (tr + 1.0) ** 0.5 * 2
        return ((m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, s / 4)
    if m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = (1.0 + m[0][0] - m[1][1] - m[2][2]) ** 0.5 * 2
        return (s / 4, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s)
    if m[1][1] > m[2][2]:
        s = (1.0 + m[1][1] - m[0][0] - m[2][2]) ** 0.5 * 2
        return ((m[0][1] + m[1][0]) / s, s / 4, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s)
    s = (1.0 + m[2][2] - m[0][0] - m[1][1]) ** 0.5 * 2
    return ((m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, s / 4, (m[1][0] - m[0][1]) / s)


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def is_identity(row, tol=1e-6):
    t = row[1:4]
    q = row[4:8]
    return max(abs(v) for v in t) < tol and abs(abs(q[3]) - 1.0) < tol


def nearest_row(rows, t, max_diff=0.02):
    i = nearest([r[0] for r in rows], t, max_diff)
    return None if i is None else rows[i]


def prepare(args):
    gt, est = read_trajectory(args.gt), read_trajectory(args.est)
    os.makedirs(args.out_dir, exist_ok=True)
    estimate, aligned = args.est, 0
    if est and gt:
        g0 = nearest_row(gt, est[0][0])
        if is_identity(est[0]) and g0 is not None and not is_identity(g0, 1e-3):
            # gt_from_est = G0 * E0^-1 with E0 = identity: the ground truth's pose at the
            # estimate's first stamp. (The ATE alignment fits positions only and leaves the
            # rotation loose when the camera mostly turns, as in fr1_rpy; a map needs it.)
            rot, tr = quat_to_matrix(*g0[4:8]), g0[1:4]
            estimate, aligned = os.path.join(args.out_dir, "estimate_aligned.txt"), 1
            with open(estimate, "w") as f:
                f.write("# %s moved into the ground truth's frame: its first pose put on the "
                        "pose of %s at %.6f\n" % (args.est, args.gt, g0[0]))
                for r in est:
                    p = [sum(rot[i][k] * r[1 + k] for k in range(3)) + tr[i] for i in range(3)]
                    q = matrix_to_quat(matmul(rot, quat_to_matrix(*r[4:8])))
                    f.write("%.6f %s %s\n" % (r[0], " ".join("%.6f" % v for v in p),
                                              " ".join("%.6f" % v for v in q)))
    reference = ""
    if est and gt:
        stamps = [t for t, _ in read_list(os.path.join(args.dataset, "rgb.txt"))]
        lo, hi = est[0][0] - 0.02, est[-1][0] + 0.02
        posed = [t for t in stamps if nearest_row(gt, t) is not None]
        in_span = [t for t in posed if lo <= t <= hi]
        if len(in_span) < len(posed):
            reference = os.path.join(args.out_dir, "groundtruth_span.txt")
            with open(reference, "w") as f:
                f.write("# %s cut to the time span of %s\n" % (args.gt, args.est))
                for r in gt:
                    if lo - 0.05 <= r[0] <= hi + 0.05:
                        f.write("%.6f %s\n" % (r[0], " ".join("%.6f" % v for v in r[1:])))
    print("estimate=%s" % estimate)
    print("aligned=%d" % aligned)
    print("reference=%s" % reference)
    return 0


# ----------------------------------------------------------------------------------------- helpers
def load_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def read_meta(path):
    meta = {}
    try:
        with open(path) as f:
            for line in f:
                if "=" in line:
                    k, v = line.rstrip("\n").split("=", 1)
                    meta[k] = v
    except OSError:
        pass
    return meta


def last_line(path):
    try:
        with open(path) as f:
            lines = [l.strip() for l in f if l.strip()]
        return lines[-1] if lines else ""
    except OSError:
        return ""


def fmt(v, digits=4, unit=""):
    if v is None:
        return "n/a"
    return ("%." + str(digits) + "f%s") % (v, unit)


def pct(v):
    return "n/a" if v is None else "%.1f%%" % (100.0 * v)


def thousands(v):
    return "n/a" if v is None else "{:,}".format(int(v))


def overall(rows):
    for r in rows or []:
        if r.get("class") == "overall":
            return r
    return None


def md_table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def short(path, data):
    if not path:
        return "—"
    if data and path.startswith(data.rstrip("/") + "/"):
        path = path[len(data.rstrip("/")) + 1:]
    parts = path.split("/")
    return "/".join(parts[-2:]) if len(parts) > 2 else path


def objects_summary(doc):
    """(reference count, mapped count, count error, matched, mean distance, mean IoU) of eval objects."""
    if not doc:
        return None
    c = overall(doc.get("counts"))
    e = overall(doc.get("centroid_error"))
    if not c or not e:
        return None
    return {
        "reference": c["reference"],
        "mapped": c["mapped"],
        "error": c["error"],
        "matched": e["matched"],
        "distance": e["distance_m"]["mean"] if e["matched"] else None,
        "iou": e["iou"]["mean"] if e["matched"] else None,
    }


def machine(objmap):
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    mem = ""
    try:
        with open("/proc/meminfo") as f:
            kb = int(f.readline().split()[1])
            mem = ", %.0f GB RAM" % (kb / 1024.0 / 1024.0)
    except (OSError, ValueError, IndexError):
        pass
    version = ""
    if objmap:
        try:
            version = subprocess.run([objmap, "--version"], capture_output=True, text=True,
                                     timeout=10).stdout.strip()
        except (OSError, subprocess.SubprocessError):
            pass
    commit = ""
    try:
        root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", root, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        if commit and dirty:
            commit += " + local changes"
    except (OSError, subprocess.SubprocessError):
        pass
    return "%s, %d cores%s, %s %s" % (cpu, os.cpu_count() or 0, mem, platform.system(),
                                      platform.release()), version, commit


# ------------------------------------------------------------------------------------------ tables
def load_sequences(bench):
    seqs = []
    for meta_path in sorted(glob.glob(os.path.join(bench, "*", "meta.txt"))):
        d = os.path.dirname(meta_path)
        if os.path.basename(d) == "perf":
            continue
        m = read_meta(meta_path)
        m["dir"] = d
        m["run_gt"] = load_json(os.path.join(d, "run_gt", "run.json"))
        m["run_est"] = load_json(os.path.join(d, "run_est", "run.json"))
        m["run_gt_span"] = load_json(os.path.join(d, "run_gt_span", "run.json"))
        m["gt_vs_truth"] = load_json(os.path.join(d, "objects_gt_vs_truth.json"))
        m["est_vs_truth"] = load_json(os.path.join(d, "objects_est_vs_truth.json"))
        m["est_vs_gtmap"] = load_json(os.path.join(d, "objects_est_vs_gtmap.json"))
        m["ate_est"] = load_json(os.path.join(d, "ate_est.json"))
        for method in ("paper", "graph"):
            m["ate_" + method] = load_json(os.path.join(d, "ate_corrected_%s.json" % method))
            m["corr_vs_gtmap_" + method] = load_json(
                os.path.join(d, "objects_corrected_%s_vs_gtmap.json" % method))
            m["correct_log_" + method] = last_line(os.path.join(d, "correct_%s.log" % method))
            m["correction_" + method] = load_json(
                os.path.join(d, "correct_" + method, "correction.json"))
        m["fuse_gt_error"] = "" if m["run_gt"] else last_line(os.path.join(d, "fuse_gt.log"))
        m["eval_truth_error"] = last_line(os.path.join(d, "eval_gt_vs_truth.log")) \
            if m.get("gt_objects") and not m["gt_vs_truth"] else ""
        seqs.append(m)
    # synthetic first, then real, by name
    seqs.sort(key=lambda s: (s.get("kind") != "synthetic", s.get("name", "")))
    return seqs


def sequences_table(seqs, data):
    rows = []
    for s in seqs:
        run = s["run_gt"]
        if s.get("skipped"):
            kf = "skipped: " + s["skipped"]
        elif run:
            c = run.get("counts", {})
            kf = "%s of %s (%s)" % (c.get("keyframes"), c.get("frames"), c.get("keyframe_mode"))
        else:
            kf = "fuse failed: " + (s["fuse_gt_error"] or "see fuse_gt.log")
        seg = short(s.get("segmentation"), data)
        if run:
            seg += " (%s)" % run.get("inputs", {}).get("segmentation", {}).get("format", "?")
        est = os.path.basename(s.get("estimate", "")) or "—"
        notes = []
        if s.get("aligned") == "1":
            notes.append("SLAM frame: its first pose put on the ground truth's")
        if s["run_gt_span"]:
            c = s["run_gt_span"].get("counts", {})
            notes.append("covers %s keyframes: reference map fused over its span" %
                         c.get("keyframes"))
        if notes:
            est += " (" + "; ".join(notes) + ")"
        rows.append([s.get("name"), s.get("frames", "?"), seg, est,
                     os.path.basename(s.get("gt_objects", "")) or "—", kf])
    return md_table(["sequence", "frames", "segmentation", "estimated trajectory",
                     "ground-truth objects", "keyframes (ground-truth run)"], rows)


def duplicates_cell(run):
    """Suspected duplicates of a run.json: "N: a+b class (why not merged), ..."; "n/a" before them."""
    d = (run or {}).get("duplicates")
    if d is None:
        return "n/a"
    pairs = ["%d+%d %s (%s)" % (p["a"], p["b"], p["class"], p["merge_refused"].replace("_", " "))
             for p in d.get("pairs", [])]
    return "%d" % d.get("count", len(pairs)) + (": " + ", ".join(pairs) if pairs else "")


def table3(seqs):
    rows = []
    for s in seqs:
        if not s["run_gt"]:
            continue
        t = objects_summary(s["gt_vs_truth"])
        e = objects_summary(s["est_vs_gtmap"])
        confirmed = s["run_gt"].get("counts", {}).get("objects_confirmed")
        if t is None and e is None:
            if s.get("gt_objects"):
                err = s["eval_truth_error"] or "?"
                err = err.split(": error: ", 1)[-1]
                note = "eval objects cannot read it: " + (err[:90] + "…" if len(err) > 90 else err)
            else:
                note = "no ground-truth objects"
            rows.append([s["name"], "—", confirmed, "—", "—", duplicates_cell(s["run_gt"]), note])
            continue
        rows.append([
            s["name"],
            t["reference"] if t else "—",
            t["mapped"] if t else confirmed,
            pct(t["error"]) if t else "—",
            ("%d / %s" % (e["mapped"], pct(e["error"]))) if e else "—",
            duplicates_cell(s["run_gt"]),
            "",
        ])
    return md_table(["sequence", "ground-truth objects", "mapped (groundtruth.txt)",
                     "count error", "mapped with the estimate / error vs that map",
                     "suspected duplicates (groundtruth.txt run: ids, class, merge rule that "
                     "refused)", "note"], rows)


def table45(seqs):
    rows = []
    for s in seqs:
        t = objects_summary(s["gt_vs_truth"])
        te = objects_summary(s["est_vs_truth"])
        e = objects_summary(s["est_vs_gtmap"])
        if not (t or e):
            continue
        ate = s["ate_est"]["rmse"] if s["ate_est"] else None
        rows.append([
            s["name"],
            fmt(ate) if s["ate_est"] else "—",
            ("%d of %d" % (e["matched"], e["reference"])) if e else "—",
            fmt(e["distance"]) if e else "—",
            fmt(e["iou"], 3) if e else "—",
            fmt(t["distance"]) if t else "—",
            fmt(t["iou"], 3) if t else "—",
            fmt(te["distance"]) if te else "—",
        ])
    rows.append(["paper, fr3_office (ORB-SLAM2)", "0.0121", "", fmt(PAPER_TABLE4_FR3_OFFICE), "",
                 "", "", ""])
    return md_table([
        "sequence", "ATE RMSE of the estimate [m]", "matched (estimate map vs ground-truth map)",
        "mean centroid error, estimate map vs ground-truth map [m]", "OBB IoU",
        "mean centroid error, ground-truth map vs true objects [m]", "OBB IoU ",
        "mean centroid error, estimate map vs true objects [m]"
    ], rows)


def table6(seqs):
    """Table 6 as the paper defines it: the objects-only map against the dense map (its 45.3-61.5%),
    last column; eq 18's own reduction (voxel-filtered -> outlier-filtered) is a column of its own."""
    rows = []
    for s in seqs:
        run = s["run_gt"]
        if not run:
            continue
        p = run.get("points", {})
        raw, vox, out = p.get("objects_raw"), p.get("objects_voxel_filtered"), \
            p.get("objects_outlier_filtered")
        dense = p.get("dense_map")
        red_outlier = (1.0 - out / vox) if vox else None
        red_total = (1.0 - out / raw) if raw else None
        red_dense = (1.0 - p.get("objects_map", 0) / dense) if dense else None
        rows.append([s["name"], thousands(p.get("dense_back_projected")), thousands(dense),
                     thousands(raw), thousands(vox), thousands(out), pct(red_outlier),
                     pct(red_total), pct(red_dense)])
    rows.append(["paper (its sequences)", "", "", "", "", "", "", "", PAPER_TABLE6_REDUCTION])
    return md_table([
        "sequence", "dense back-projected", "dense map (1 cm voxels)", "object points raw",
        "voxel-filtered", "outlier-filtered (eq 18)",
        "eq 18's own reduction (voxel-filtered → outlier-filtered)",
        "object points raw → outlier-filtered", "Table 6: objects-only map vs dense map"
    ], rows)


def correct_speed(bench):
    """One line: objmap correct on the 200-keyframe synthetic run, per view model."""
    d = os.path.join(bench, "correct_speed")
    cells = []
    for v in ("icp", "visible"):
        m = load_json(os.path.join(d, "correct_%s.json" % v))
        c = load_json(os.path.join(d, "correction_%s.json" % v))
        if not m or not c:
            continue
        counts = c.get("counts", {})
        cells.append("--view-model %s: %.1f s wall, %.1f s CPU, %.0f MB (%s keyframes, %s "
                     "observations, %s view links of %s pairs)" % (
                         v, m["seconds"], m["cpu_seconds"], m["peak_rss_mb"],
                         counts.get("keyframes", "?"), counts.get("observations", "?"),
                         counts.get("view_links", 0), counts.get("view_links_tried", 0)))
    if not cells:
        return "Speed of objmap correct on 200 keyframes: not measured (BENCH_PERF=0 or no correct)."
    return ("Speed of `objmap correct` (graph, with the re-fuse when accepted) on a 200-keyframe "
            "synthetic run (`objmap synth --seed 1 --frames 200 --orbit-speed 60`, fused with "
            "estimated.txt): " + "; ".join(cells) + ".")


def table7(seqs, has_correct):
    rows = []
    for s in seqs:
        if not s["ate_est"]:
            continue
        name = s["name"]
        if os.path.basename(s.get("estimate", "")).startswith("drifted_seed"):
            name += " (drifted copy of groundtruth.txt, seed 1)"
        cells = [name, str(s["ate_est"]["pairs"]), fmt(s["ate_est"]["rmse"])]
        for method in ("paper", "graph"):
            a = s["ate_" + method]
            if not has_correct:
                cells.append("n/a (objmap correct not built)")
            elif a:
                c = s["correction_" + method] or {}
                before = s["ate_est"]["rmse"]
                note = ""
                if c.get("accepted") is False:
                    note = " (refused, poses kept: %s)" % c.get("reason", "?").replace(
                        "refused: ", "")
                elif c.get("accepted"):
                    change = ("%+.1f%%, " % (100.0 * (a["rmse"] - before) / before)
                              if before > 0 else "")
                    note = " (%s%s of %s keyframes corrected%s)" % (
                        change, c.get("counts", {}).get("keyframes_corrected", "?"),
                        c.get("counts", {}).get("keyframes", "?"),
                        ", view links" if c.get("view_links_used") else "")
                cells.append(fmt(a["rmse"]) + note)
            else:
                cells.append("failed: " + (s["correct_log_" + method] or "no corrected trajectory"))
            c = objects_summary(s["corr_vs_gtmap_" + method])
            cells.append(fmt(c["distance"]) if c else "—")
        rows.append(cells)
    ours = md_table([
        "sequence", "pairs", "estimate ATE RMSE [m]", "corrected, --method paper [m]",
        "its map vs ground-truth map [m]", "corrected, --method graph [m]",
        "its map vs ground-truth map [m] "
    ], rows)
    paper = md_table(["paper, ATE RMSE [m]"] + PAPER_TABLE7["sequences"], [
        [k] + ["%.4f" % v for v in PAPER_TABLE7[k]] for k in ("ORB-SLAM2", "Ours (paper)")
    ])
    return ours + "\n\nThe paper's Table 7 on its sequences (not in DATA here):\n\n" + paper


def parse_bench_fuse(text):
    out = {}
    for key, pattern in (
            ("fuse_ms", r"^fuse, (\d+) threads?\s+([\d.]+) ms"),
            ("decode1_ms", r"^decode, 1 thread\s+([\d.]+) ms"),
            ("decoden_ms", r"^decode, (\d+) threads\s+([\d.]+) ms"),
            ("imread1_ms", r"^OpenCV imread, 1 thr\s+([\d.]+) ms"),
            ("startup_ms", r"^objmap start-up\s+([\d.]+) ms"),
            ("rss_mb", r"^peak RSS\s+([\d.]+) MB"),
            ("keyframes", r"\((\d+) keyframes"),
    ):
        m = re.search(pattern, text, re.M)
        if m:
            out[key] = float(m.groups()[-1])
            if key in ("decoden_ms", "fuse_ms"):
                out[key + "_threads"] = int(m.group(1))
    return out

STEPS_HEADER = ["step of `objmap fuse` (run.json of the best run)", "ms per keyframe",
                "last committed", "change"]
GREW_SHARE, GREW_MS = 0.10, 0.25  # a step grew: by more than 10% and 0.25 ms per keyframe


def fuse_steps(best, bf):
    """(name, ms per keyframe) of each step of the best fuse run (run.json performance.seconds),
    then the whole command, the start-up and the ratio to cv::imread's decoding (bench_fuse)."""
    measured, rj = best
    kf = rj["counts"]["keyframes"]
    rows = [(name, 1000.0 * sec / kf)
            for name, sec in rj.get("performance", {}).get("seconds", {}).items()]
    whole = 1000.0 * measured["seconds"] / kf
    rows.append(("whole command (wall)", whole))
    if "startup_ms" in bf:
        rows.append(("objmap start-up (once per command, per keyframe here)",
                     bf["startup_ms"] / kf))
    if "imread1_ms" in bf:
        rows.append(("whole command / cv::imread of its PNGs (ratio, not ms)",
                     whole / bf["imread1_ms"]))
    return rows


def committed_steps(doc):
    """The step figures of the fuse-steps table of `doc` as last committed (git show HEAD:doc),
    else as the file is now; ({name: value}, where they come from)."""
    text, origin = "", ""
    if doc:
        folder = os.path.dirname(os.path.abspath(doc))
        try:
            root = subprocess.run(["git", "-C", folder, "rev-parse", "--show-toplevel"],
                                  capture_output=True, text=True, timeout=10).stdout.strip()
            if root:
                rel = os.path.relpath(os.path.abspath(doc), root)
                got = subprocess.run(["git", "-C", root, "show", "HEAD:" + rel],
                                     capture_output=True, text=True, timeout=10)
                head = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                                      capture_output=True, text=True, timeout=10).stdout.strip()
                if got.returncode == 0:
                    text, origin = got.stdout, "%s as committed in git %s" % (rel, head)
        except (OSError, subprocess.SubprocessError):
            pass
        if not text:
            try:
                with open(doc) as f:
                    text, origin = f.read(), doc
            except OSError:
                pass
    header = "| " + " | ".join(STEPS_HEADER) + " |"
    if header not in text:
        return {}, origin
    values = {}
    for line in text[text.index(header):].splitlines()[2:]:
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not line.startswith("|") or len(cells) < 2:
            break
        try:
            values[cells[0]] = float(cells[1])
        except ValueError:
            pass
    return values, origin


def compare_steps(rows, previous, origin):
    """The fuse-steps table with the last committed figures beside, and a sentence naming the
    steps that grew (GREW_SHARE and GREW_MS)."""
    table, grew = [], []
    for name, now in rows:
        before = previous.get(name)
        change = ""
        if before is not None:
            change = "%+.2f" % (now - before)
            if before > 0:
                change += " (%+.0f%%)" % (100.0 * (now - before) / before)
            if "ratio" not in name and now - before > max(GREW_MS, GREW_SHARE * before):
                grew.append("%s (%+.2f ms per keyframe, %+.0f%%)" %
                            (name, now - before, 100.0 * (now - before) / before))
        table.append([name, "%.2f" % now, "" if before is None else "%.2f" % before, change])
    if not previous:
        verdict = ("No earlier figures to compare with (%s)." %
                   (origin + " has no fuse-steps table" if origin else "no document given"))
    elif grew:
        verdict = "Grew since the last committed figures (%s): %s." % (origin, "; ".join(grew))
    else:
        verdict = ("No step grew by more than %d%% and %.2f ms per keyframe since the last "
                   "committed figures (%s)." % (100 * GREW_SHARE, GREW_MS, origin))
    return md_table(STEPS_HEADER, table), verdict


def performance(bench, doc=""):
    perf = os.path.join(bench, "perf")
    meta = read_meta(os.path.join(perf, "meta.txt"))
    if not meta.get("dataset"):
        return "Not measured (no fr1_rpy_every4 in DATA, or BENCH_PERF=0).", None
    runs = []
    for f in sorted(glob.glob(os.path.join(perf, "objmap_[0-9]*.json"))):
        m = load_json(f)
        rj = load_json(f.replace("objmap_", "objmap_run_"))
        if m and m.get("exit_code") == 0 and rj:
            runs.append((m, rj))
    bf_text = ""
    try:
        with open(os.path.join(perf, "bench_fuse.txt")) as f:
            bf_text = f.read()
    except OSError:
        pass
    bf = parse_bench_fuse(bf_text)
    o3d = load_json(os.path.join(perf, "open3d.json"))
    o3d_note = last_line(os.path.join(perf, "open3d.log"))

    rows = []
    fuse_ms = cpu_ms = None
    if runs:
        best = min(runs, key=lambda r: r[0]["seconds"])
        kf = best[1]["counts"]["keyframes"]
        fuse_ms = 1000.0 * best[0]["seconds"] / kf
        cpu_ms = 1000.0 * min(r[0]["cpu_seconds"] for r in runs) / kf
        rss = max(r[0]["peak_rss_mb"] for r in runs)
        rows.append(["`objmap fuse` (whole command: read, fuse, filter, write), best of %d" %
                     len(runs), "%d keyframes" % kf, fmt(fuse_ms, 1), fmt(cpu_ms, 1),
                     fmt(rss, 0, " MB"), "", ""])
    else:
        rows.append(["`objmap fuse`", "", "failed", "", "", "", ""])
    if "decode1_ms" in bf:
        kf = "%d keyframes" % bf["keyframes"] if "keyframes" in bf else ""
        rows.append(["PNG decode floor, 1 thread (bench_fuse: rgb + depth of the same keyframes, "
                     "objmap's reader, as fuse decodes them)",
                     kf, fmt(bf["decode1_ms"], 1), fmt(bf["decode1_ms"], 1), "",
                     "fuse / decode = " + fmt(fuse_ms / bf["decode1_ms"], 2) if fuse_ms else "n/a",
                     "fuse / decode = " + fmt(cpu_ms / bf["decode1_ms"], 2) if cpu_ms else "n/a"])
        if "decoden_ms" in bf:
            rows.append(["PNG decode floor, %d threads" % bf["decoden_ms_threads"], kf,
                         fmt(bf["decoden_ms"], 1), "", "",
                         "fuse / decode = " + fmt(fuse_ms / bf["decoden_ms"], 2)
                         if fuse_ms else "n/a", ""])
        if "imread1_ms" in bf:
            rows.append(["the same PNGs with OpenCV's cv::imread (libpng, zlib), 1 thread", kf,
                         fmt(bf["imread1_ms"], 1), "", "",
                         "fuse / imread = " + fmt(fuse_ms / bf["imread1_ms"], 2)
                         if fuse_ms else "n/a", ""])
    else:
        rows.append(["PNG decode floor (bench_fuse)", "", "n/a (" +
                     (last_line(os.path.join(perf, "bench_fuse.txt")) or "not run") + ")", "",
                     "", "", ""])
    if o3d:
        rows.append(["Open3D %s (scripts/open3d_baseline.py: back-project, concatenate, 1 cm voxel "
                     "filter, statistical outliers)" % o3d.get("open3d", ""),
                     "%d frames" % o3d["frames"], fmt(o3d["ms_per_frame"], 1),
                     fmt(o3d.get("cpu_ms_per_frame"), 1), fmt(o3d["peak_rss_mb"], 0, " MB"),
                     "Open3D / fuse = " + fmt(o3d["ms_per_frame"] / fuse_ms, 2)
                     if fuse_ms else "n/a",
                     "Open3D / fuse = " + fmt(o3d["cpu_ms_per_frame"] / cpu_ms, 2)
                     if cpu_ms and o3d.get("cpu_ms_per_frame") else "n/a"])
    else:
        rows.append(["Open3D", "", "n/a (%s)" % (o3d_note or "not run"), "", "", "", ""])
    table = md_table(["job on fr1_rpy_every4, groundtruth.txt", "frames", "wall ms per frame",
                      "CPU ms per frame", "peak RSS", "ratio, wall", "ratio, CPU"],
                     rows)
    summary = []
    if fuse_ms and o3d:
        summary.append("objmap fuse is %.1f× faster than the Open3D job per frame (wall; %s× in "
                       "CPU time) and uses %.1f× less memory at peak." %
                       (o3d["ms_per_frame"] / fuse_ms,
                        fmt(o3d.get("cpu_ms_per_frame", 0) / cpu_ms, 1) if cpu_ms else "n/a",
                        o3d["peak_rss_mb"] / max(r[0]["peak_rss_mb"] for r in runs)))
    if fuse_ms and "decode1_ms" in bf:
        summary.append("The whole fuse costs %.2f× the mere decoding of its PNGs on one thread in "
                       "wall time, %.2f× in CPU time." %
                       (fuse_ms / bf["decode1_ms"], cpu_ms / bf["decode1_ms"]))
        if "imread1_ms" in bf:
            summary.append("objmap decodes these PNGs with libdeflate (the same pixels as "
                           "OpenCV): %.2f× faster than cv::imread; against cv::imread the fuse "
                           "costs %.2f× the decoding." %
                           (bf["imread1_ms"] / bf["decode1_ms"], fuse_ms / bf["imread1_ms"]))
    summary.append("Reference for the Open3D job on this machine: ~214 ms/frame, 2.7 GB.")
    steps = ""
    if runs:
        steps_table, verdict = compare_steps(fuse_steps(best, bf), *committed_steps(doc))
        print("fuse steps: " + verdict, file=sys.stderr)
        steps = ("\n\nEach step of that run, per keyframe, against the figures of this table as "
                 "last committed (the steps \"parallel to the objects\" run beside the merge and "
                 "filter, so the steps do not add up to the whole):\n\n" + steps_table +
                 "\n\n" + verdict)
    return table + "\n\n" + " ".join(summary) + steps, meta["dataset"]


def network_chain(bench):
    """The network chain's table (scripts/network_chain.sh), when the bench ran it."""
    path = os.path.join(bench, "network_chain.md")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        table = f.read().strip()
    if not table:
        return []
    return [
        "### Real-data maps: detector boxes beside YOLOv5n-seg masks",
        "",
        "`scripts/network_chain.sh`: detect -> track -> fuse (groundtruth.txt) -> `eval masks` on "
        "each real sequence, with the sequence's detector boxes and with YOLOv5n-seg's instance "
        "masks (480x640 ONNX). The mask column: of each object's points that a keyframe where it "
        "was observed sees, the share inside that observation's own mask (no ground truth needed).",
        "",
        table,
        "",
    ]


def render(args):
    bench = os.path.abspath(args.bench)
    data = os.path.abspath(args.data) if args.data else ""
    features = read_meta(os.path.join(bench, "features.txt"))
    has_correct = features.get("has_correct") == "1"
    seqs = load_sequences(bench)
    cpu, version, commit = machine(args.objmap)
    date = features.get("date") or datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M UTC")
    took = " in %.0f min" % (args.seconds / 60.0) if args.seconds else ""
    perf_text, _ = performance(bench, args.doc)

    parts = [
        BEGIN,
        "## Measured by `make bench` (generated section)",
        "",
        "Generated by `%s` on %s%s; %s%s; machine: %s, load average %s at the start "
        "(other jobs share the cores: wall times vary, CPU times are steadier). Everything between "
        "the bench markers of this file is replaced on each run; the JSON of every evaluation is "
        "in `out/bench/<sequence>/`. Synthetic scenes: `objmap synth --seed N --orbit-speed 60` "
        "(exact objects, `estimated.txt` drifts 2%% of the path). Each sequence is fused with "
        "groundtruth.txt and with its estimated trajectory; `eval objects` matches objects "
        "one-to-one by class within 0.3 m." % (
            args.command, date, took, version or "objmap",
            (" (git " + commit + ")") if commit else "", cpu, features.get("load_start", "?")),
        "",
        "### Sequences found",
        "",
        sequences_table(seqs, data),
        "",
        "### Table 3: object count (map fused with groundtruth.txt vs the ground-truth objects)",
        "",
        table3(seqs),
        "",
        "The paper's Table 3 counts the objects of its own TUM sequences (fr3_office and others), "
        "which are not in DATA here. Suspected duplicates need no ground truth: objmap's own "
        "check (run.json `duplicates`, docs/formats.md) lists pairs of objects of one class whose "
        "boxes overlap or whose surfaces touch, and the merge-pass rule that kept each pair apart "
        "(shared frames: seen together, likely two objects; score or overlap: the likelier "
        "duplicate).",
        "",
        "### Tables 4–5: centroid error",
        "",
        "The paper's protocol: the map fused with the estimated trajectory against the map fused "
        "with the ground-truth trajectory (objects matched one-to-one by class); beside it, both "
        "maps against the true objects where the sequence has them (synthetic: volume centroids; "
        "fr3_cabinet: the cuboid centre).",
        "",
        table45(seqs),
        "",
        "### Table 6: points of the object clouds (map fused with groundtruth.txt)",
        "",
        "The paper's Table 6 figure (45.3–61.5%) is the objects-only map against the dense map: "
        "the last column, 1 − objects_map / dense_map. Eq 18's own reduction, the share of the "
        "voxel-filtered object points that the statistical outlier filter removes, is a column of "
        "its own (1 − outlier-filtered / voxel-filtered); the paper gives no figure for it.",
        "",
        table6(seqs),
        "",
        "### Table 7: ATE RMSE before and after the object-constrained pose correction",
        "",
        table7(seqs, has_correct),
        "",
        correct_speed(bench),
        "",
        "### Performance: objmap fuse vs the PNG-decode floor vs Open3D",
        "",
        perf_text,
        "",
    ] + network_chain(bench) + [
        END,
    ]
    section = "\n".join(parts)
    os.makedirs(bench, exist_ok=True)
    with open(os.path.join(bench, "tables.md"), "w") as f:
        f.write(section.replace(BEGIN + "\n", "").replace("\n" + END, "") + "\n")

    if args.doc:
        write_section(args.doc, section)
    print(section)
    return 0


def write_section(doc, section, begin=BEGIN, end=END, after_intro=True):
    """Replaces the part of `doc` from the line `begin` to the line `end` with `section`; without
    the markers `section` goes after the intro (before the first "## " heading: after_intro) or at
    the end."""
    try:
        with open(doc) as f:
            text = f.read()
    except OSError:
        text = "# Benchmarks and measured results\n\n" if after_intro else ""
    m = re.search(r"^## ", text, re.M) if after_intro else None
    if begin in text and end in text and text.index(begin) < text.index(end):
        before = text[:text.index(begin)]
        after = text[text.index(end) + len(end):]
        new = before + section + after
    elif m:
        new = text[:m.start()] + section + "\n\n" + text[m.start():]
    else:
        new = (text.rstrip("\n") + "\n\n" if text.strip() else "") + section + "\n"
    tmp = doc + ".tmp"
    with open(tmp, "w") as f:
        f.write(new)
    os.replace(tmp, doc)


def add_render_arguments(parser, command):
    """The options of a render step that says how and by what it was made (ablation_tables too)."""
    parser.add_argument("--doc", default="")
    parser.add_argument("--objmap", default="")
    parser.add_argument("--command", default=command)
    parser.add_argument("--seconds", type=float, default=0.0)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="what", required=True)
    m = sub.add_parser("measure", help="run a command, record wall, CPU and peak RSS")
    m.add_argument("--json", required=True)
    m.add_argument("cmd", nargs=argparse.REMAINDER)
    q = sub.add_parser("prepare", help="the estimate in the ground truth's frame and time span")
    for k in ("--dataset", "--gt", "--est", "--out-dir"):
        q.add_argument(k, required=True)
    r = sub.add_parser("render", help="write the Markdown tables")
    r.add_argument("--bench", default="out/bench")
    r.add_argument("--data", default="")
    add_render_arguments(r, "make bench")
    args = p.parse_args()
    return {"measure": measure, "prepare": prepare, "render": render}[args.what](args)


if __name__ == "__main__":
    sys.exit(main())
