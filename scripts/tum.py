"""TUM RGB-D files for objmap's Python scripts (stdlib only): listings, trajectories, timestamp
association and quaternions. Bad input: one line `<prog>: error: <file:line>: <reason>`, exit 2."""
import bisect
import os
import sys


def fail(where, reason):
    prog = os.path.splitext(os.path.basename(sys.argv[0]))[0]
    sys.stderr.write("%s: error: %s: %s\n" % (prog, where, reason))
    sys.exit(2)


def _rows(path):
    """(line number, fields) of every non-empty, non-comment line of `path`."""
    try:
        with open(path) as f:
            for n, line in enumerate(f, 1):
                parts = line.split()
                if parts and not parts[0].startswith("#"):
                    yield n, parts
    except OSError as e:
        fail(path, "cannot read (%s)" % e.strerror)


def read_list(path):
    """rgb.txt / depth.txt: sorted (timestamp, filename) pairs."""
    rows = []
    for n, parts in _rows(path):
        if len(parts) < 2:
            fail("%s:%d" % (path, n), "%d fields; expected 2: timestamp filename" % len(parts))
        rows.append((float(parts[0]), parts[1]))
    rows.sort()
    return rows


def read_trajectory(path):
    """TUM trajectory: sorted rows [timestamp, tx, ty, tz, qx, qy, qz, qw]."""
    rows = []
    for n, parts in _rows(path):
        if len(parts) != 8:
            fail("%s:%d" % (path, n),
                 "%d fields; expected 8: timestamp tx ty tz qx qy qz qw" % len(parts))
        try:
            rows.append([float(v) for v in parts])
        except ValueError:
            fail("%s:%d" % (path, n), "a field is not a number; expected 8 numbers")
    rows.sort()
    return rows


def nearest(stamps, t, max_diff):
    """Index of the sorted `stamps` nearest to t within max_diff, else None."""
    i = bisect.bisect_left(stamps, t)
    best = None
    for j in (i - 1, i):
        if 0 <= j < len(stamps) and abs(stamps[j] - t) <= max_diff:
            if best is None or abs(stamps[j] - t) < abs(stamps[best] - t):
                best = j
    return best


def quat_to_matrix(qx, qy, qz, qw):
    """Rotation matrix (3x3 nested lists) of a quaternion, normalised first."""
    n = (qx * qx + qy * qy + qz * qz + qw * qw) ** 0.5
    qx, qy, qz, qw = qx / n, qy / n, qz / n, qw / n
    return [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
            [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
            [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
