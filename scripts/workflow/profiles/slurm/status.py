#!/usr/bin/env python3
"""Snakemake --cluster-status for Slurm without an accounting database: prints running, success
or failed for a job id, from `scontrol show job` (Slurm keeps a finished job there for MinJobAge,
300 s by default), else from `sacct` where accounting is set up."""
import subprocess
import sys

RUNNING = {"PENDING", "CONFIGURING", "RUNNING", "COMPLETING", "SUSPENDED", "REQUEUED", "RESIZING",
           "STAGE_OUT", "SIGNALING"}


def state_of(job):
    r = subprocess.run(["scontrol", "-o", "show", "job", job], capture_output=True, text=True)
    for field in r.stdout.split():
        if field.startswith("JobState="):
            return field.split("=", 1)[1]
    r = subprocess.run(["sacct", "-n", "-X", "-P", "-o", "State", "-j", job], capture_output=True,
                       text=True)
    lines = r.stdout.split()
    return lines[0].split()[0] if r.returncode == 0 and lines else None


job = sys.argv[1].split(";")[0]
state = state_of(job)
if state is None or state in RUNNING:
    print("running")  # not known yet or any more: Snakemake's own job markers decide
elif state == "COMPLETED":
    print("success")
else:
    print("failed")
