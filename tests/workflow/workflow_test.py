#!/usr/bin/env python3
"""The Snakemake workflow (scripts/workflow/Snakefile) on three small recordings with the local executor on
2 cores: two synthetic scenes (one with pose correction) and the real ycbv_0000_10f clip of
../shared/data when present (else a third synthetic scene).

  workflow_test.py OBJMAP_BINARY SOURCE_DIR

Checks: every output; the summary's figures equal to each run's own run.json, objects.json and eval
JSON; a second invocation has nothing to do; deleting one run's map/objects.json reruns that
recording's fuse and the stages after it, and nothing else; a recording with a broken trajectory
fails alone (the others complete) and the summary names it with the stage and the error line.
Exit 77 (skipped) when snakemake is not installed."""
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

SKIP = 77
failures = []
STARTED = time.monotonic()


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def snakemake(step, args, cwd):
    """One snakemake invocation; its whole console output is kept in cwd/snakemake_STEP.log (the
    folder is kept when a check fails), and a line says when it ended, so that a run cut short by
    ctest's time limit shows which step it was in and how long each took."""
    start = time.monotonic()
    r = subprocess.run(["snakemake", "-s", SNAKEFILE, "--cores", "2"] + args, cwd=cwd,
                       capture_output=True, text=True)
    with open(os.path.join(cwd, f"snakemake_{step}.log"), "w") as f:
        f.write(r.stdout + r.stderr)
    print(f"[{time.monotonic() - STARTED:.1f} s] snakemake {step}: exit {r.returncode} "
          f"in {time.monotonic() - start:.1f} s", flush=True)
    return r


def rules_run(output):
    """(rule, recording) of every job a snakemake run started."""
    jobs, rule = [], None
    for line in output.splitlines():
        if line.startswith("rule ") or line.startswith("localrule "):
            rule = line.split()[1].rstrip(":")
            if rule in ("all", "summary"):
                jobs.append((rule, None))
                rule = None
        elif rule and line.strip().startswith("wildcards:"):
            name = [w.split("=")[1] for w in line.split(":", 1)[1].split(", ") if w.strip().startswith("name=")]
            jobs.append((rule, name[0] if name else None))
            rule = None
    return jobs


def write_manifest(path, rows):
    header = ["name", "dataset", "trajectory", "segmentation", "gt_trajectory", "gt_objects", "correct"]
    with open(path, "w") as f:
        f.write("# recordings of the workflow test\n" + "\t".join(header) + "\n")
        for r in rows:
            f.write("\t".join(r.get(c, "-") or "-" for c in header) + "\n")


def load(path):
    with open(path) as f:
        return json.load(f)


def overall(rows):
    return next(r for r in rows if r["class"] == "overall")


def check_summary_figures(results, names):
    summary = load(os.path.join(results, "summary", "summary.json"))
    by_name = {r["name"]: r for r in summary["recordings"]}
    check(sorted(by_name) == sorted(names), f"summary names {sorted(by_name)}")
    with open(os.path.join(results, "summary", "summary.csv"), newline="") as f:
        rows = {r["name"]: r for r in csv.DictReader(f)}
    for name in names:
        s, run = by_name[name], os.path.join(results, name)
        check(s["status"] == "ok", f"{name}: status {s['status']} {s['error']}")
        mapdir = os.path.join(run, s["map"])
        objects = load(os.path.join(mapdir, "objects.json"))["objects"]
        run_json = load(os.path.join(mapdir, "run.json"))
        per_class = {}
        for o in objects:
            per_class[o["class"]] = per_class.get(o["class"], 0) + 1
        check(s["objects"] == len(objects) and s["objects_per_class"] == per_class,
              f"{name}: objects {s['objects']} {s['objects_per_class']} vs {per_class}")
        check(s["keyframes"] == run_json["counts"]["keyframes"], f"{name}: keyframes")
        check(s["duplicates"] == run_json["duplicates"]["count"], f"{name}: duplicates")
        ate = load(os.path.join(run, "eval", "ate.json"))
        rpe = load(os.path.join(run, "eval", "rpe.json"))
        ev = load(os.path.join(run, "eval", "objects.json"))
        check(s["ate_rmse_m"] == ate["rmse"], f"{name}: ATE {s['ate_rmse_m']} vs {ate['rmse']}")
        check(s["rpe_translational_rmse_m"] == rpe["translational"]["rmse"], f"{name}: RPE")
        check(s["rpe_rotational_rmse_deg"] == rpe["rotational"]["rmse"], f"{name}: RPE rot")
        check(s["gt_objects"] == overall(ev["counts"])["reference"], f"{name}: gt objects")
        check(s["matched_objects"] == overall(ev["centroid_error"])["matched"], f"{name}: matched")
        check(s["centroid_error_mean_m"] == overall(ev["centroid_error"])["distance_m"]["mean"],
              f"{name}: centroid error")
        stages = {c["stage"] for c in s["stages"]}
        check({"track", "fuse", "eval_ate", "eval_rpe", "eval_objects", "report"} <= stages,
              f"{name}: stages {stages}")
        check(all(c["seconds"] > 0 and c["max_rss_mb"] > 1 for c in s["stages"]),
              f"{name}: time and memory of every stage {s['stages']}")
        # The CSV row carries the same numbers (shortest round-trip text).
        check(float(rows[name]["ate_rmse_m"]) == ate["rmse"] and int(rows[name]["objects"]) == len(objects),
              f"{name}: CSV row {rows[name]['ate_rmse_m']} {rows[name]['objects']}")
    return summary


def mtimes(results, names):
    out = {}
    for name in names:
        for root, _, files in os.walk(os.path.join(results, name)):
            for f in files:
                p = os.path.join(root, f)
                if "/logs/" not in p and "/benchmarks/" not in p:
                    out[p] = os.stat(p).st_mtime_ns
    return out


def make_recordings(tmp):
    rows = []
    for seed in (1, 2):
        scene = os.path.join(tmp, f"scene{seed}")
        r = subprocess.run([OBJMAP, "synth", "--out", scene, "--seed", str(seed), "--frames", "30",
                            "--scale", "0.5"], capture_output=True, text=True)
        check(r.returncode == 0, f"synth: {r.stderr}")
        rows.append({"name": f"synthetic{seed}", "dataset": f"scene{seed}", "trajectory": f"scene{seed}/estimated.txt",
                     "segmentation": f"scene{seed}/segmentation", "gt_trajectory": f"scene{seed}/groundtruth.txt",
                     "gt_objects": f"scene{seed}/objects_gt.json", "correct": "yes" if seed == 1 else "no"})
    data = os.environ.get("OBJMAP_DATA") or os.path.join(SOURCE, "..", "shared", "data")
    ycbv = os.path.abspath(os.path.join(data, "ycbv_0000_10f"))
    if os.path.isdir(ycbv):
        rows.append({"name": "ycbv", "dataset": ycbv, "trajectory": f"{ycbv}/groundtruth.txt",
                     "segmentation": f"{ycbv}/masks", "gt_trajectory": f"{ycbv}/groundtruth.txt",
                     "gt_objects": f"{ycbv}/objects_gt.txt"})
    else:
        print("note: no ycbv_0000_10f under", data, "- a third synthetic scene instead")
        rows.append(dict(rows[1], name="synthetic3", correct="no"))
    return rows


def main():
    if shutil.which("snakemake") is None:
        print("skipped: snakemake is not installed (scripts/install-deps.sh installs it)")
        return SKIP
    tmp = tempfile.mkdtemp(prefix="objmap-workflow-")
    try:
        rows = make_recordings(tmp)
        names = [r["name"] for r in rows]
        write_manifest(os.path.join(tmp, "recordings.tsv"), rows)
        config = ["--config", "manifest=recordings.tsv", "results=results", f"objmap={OBJMAP}"]
        results = os.path.join(tmp, "results")

        first = snakemake("first", config, tmp)
        check(first.returncode == 0, f"first run: exit {first.returncode}: " + first.stderr[-3000:])
        for name in names:
            for f in ("track/tracks.json", "map/objects.json", "map/run.json", "eval/ate.json",
                      "eval/rpe.json", "eval/objects.json", "report/report.html", "benchmarks/fuse.tsv"):
                check(os.path.isfile(os.path.join(results, name, f)), f"{name}/{f} missing")
        for f in ("corrected/objects.json", "corrected/trajectory_corrected.txt", "eval/ate_corrected.json"):
            check(os.path.isfile(os.path.join(results, "synthetic1", f)), f"synthetic1/{f} missing")
        for f in ("summary.md", "summary.csv", "summary.json", "objects.svg", "errors.svg"):
            check(os.path.isfile(os.path.join(results, "summary", f)), f"summary/{f} missing")
        check_summary_figures(results, names)

        again = snakemake("again", config + ["-n"], tmp)
        check("Nothing to be done" in again.stdout + again.stderr,
              "second invocation: " + (again.stdout + again.stderr)[:3000])

        before = mtimes(results, names)
        os.remove(os.path.join(results, names[1], "map", "objects.json"))
        rerun = snakemake("rerun", config, tmp)
        check(rerun.returncode == 0, f"rerun: exit {rerun.returncode}: " + rerun.stderr[-3000:])
        jobs = rules_run(rerun.stdout + rerun.stderr)
        expected = {("fuse", names[1]), ("eval_ate", names[1]), ("eval_rpe", names[1]),
                    ("eval_objects", names[1]), ("report", names[1]), ("summary", None)}
        check(set(jobs) - {("all", None)} == expected, f"after deleting objects.json ran {sorted(map(str, jobs))}")
        after = mtimes(results, names)
        changed = sorted(p for p in before if after.get(p) != before[p])
        check(all(f"/{names[1]}/" in p for p in changed) and
              os.path.join(results, names[1], "track", "tracks.json") not in changed,
              f"files rewritten outside {names[1]}'s later stages: {changed[:5]}")

        with open(os.path.join(tmp, "broken.txt"), "w") as f:
            f.write("1700000000.1 0 0 0\n")
        write_manifest(os.path.join(tmp, "recordings.tsv"), rows + [dict(rows[1], name="broken", trajectory="broken.txt", correct="no")])
        broken = snakemake("broken", config + ["--keep-going"], tmp)
        check(broken.returncode != 0, "a failed recording must make snakemake fail")
        jobs = rules_run(broken.stdout + broken.stderr)
        check(all(n == "broken" for r, n in jobs if n), f"only the broken recording runs: {jobs}")
        summary = load(os.path.join(results, "summary", "summary.json"))
        bad = next((r for r in summary["recordings"] if r["name"] == "broken"), None)
        check(bad is not None and bad["status"] == "failed" and bad["failed_stage"] == "fuse"
              and "broken.txt:1:" in (bad["error"] or ""), f"summary of the broken one: {bad}")
        check(summary["totals"]["ok"] == 3 and summary["totals"]["failed"] == 1, f"totals {summary['totals']}")
        md = open(os.path.join(results, "summary", "summary.md")).read()
        check("- broken: stage fuse: `objmap: error:" in md, "summary.md names the failure")
    finally:
        if failures:
            print("kept", tmp)
        else:
            shutil.rmtree(tmp, ignore_errors=True)
    print("workflow test:", "FAILED" if failures else "ok")
    return 1 if failures else 0


if __name__ == "__main__":
    OBJMAP = os.path.abspath(sys.argv[1])
    SOURCE = os.path.abspath(sys.argv[2])
    SNAKEFILE = os.path.join(SOURCE, "scripts", "workflow", "Snakefile")
    sys.exit(main())
