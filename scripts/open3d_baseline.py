#!/usr/bin/env python3
"""The plain dense-map job of `objmap fuse` done with Open3D, for the performance table of make bench.

For every frame of a TUM RGB-D folder that has a depth image and a pose (nearest timestamps within
--max-diff seconds, as objmap associates them): read rgb + depth, back-project with the camera
intrinsics and the depth factor, transform with the frame's world_from_cam pose, concatenate. Then
voxel-filter the whole cloud at --voxel metres and remove statistical outliers (--nb-neighbors,
--std-ratio). Prints a human summary on stderr and one JSON line on stdout:
  {"frames": N, "seconds": S, "ms_per_frame": .., "cpu_ms_per_frame": .., "peak_rss_mb": ..,
   "points_back_projected": ..,
   "points_voxel": .., "points_final": .., "open3d": "0.16.1", ...}
Peak RSS is this process's (resource.getrusage). Needs Debian's python3-open3d (numpy comes with it).

  python3 scripts/open3d_baseline.py --dataset DIR --trajectory DIR/groundtruth.txt
      [--camera fr1|fr2|fr3|camera.json] [--depth-factor 5000] [--max-depth 4] [--voxel 0.01]
      [--keyframes all|motion] [--max-frames N]

--keyframes motion selects frames as objmap's default does for a dense trajectory (a new keyframe after
0.05 m or 5 degrees of motion since the last one); all (default) takes every posed frame.
"""
import argparse
import json
import math
import os
import resource
import sys
import time

from tum import fail, nearest, quat_to_matrix, read_list, read_trajectory

PRESETS = {  # TUM RGB-D intrinsics (fx, fy, cx, cy), 640x480
    "fr1": (517.3, 516.5, 318.6, 255.3),
    "fr2": (520.9, 521.0, 325.1, 249.7),
    "fr3": (535.4, 539.2, 320.1, 247.6),
}


def pose_matrix(tx, ty, tz, qx, qy, qz, qw):
    r = quat_to_matrix(qx, qy, qz, qw)
    return [r[0] + [tx], r[1] + [ty], r[2] + [tz], [0.0, 0.0, 0.0, 1.0]]


def camera_for(args):
    """(fx, fy, cx, cy, width, height, depth_factor) from --camera, camera.json or the folder name."""
    depth_factor = 5000.0
    cam = args.camera
    if cam is None and os.path.exists(os.path.join(args.dataset, "camera.json")):
        cam = os.path.join(args.dataset, "camera.json")
    if cam is None:
        name = os.path.basename(os.path.normpath(args.dataset)).lower()
        for key, alias in (("fr1", "freiburg1"), ("fr2", "freiburg2"), ("fr3", "freiburg3")):
            if key in name or alias in name:
                cam = key
                break
    if cam in PRESETS:
        fx, fy, cx, cy = PRESETS[cam]
        width, height = 640, 480
    elif cam is not None and cam.endswith(".json"):
        with open(cam) as f:
            j = json.load(f)
        try:
            fx, fy, cx, cy = (float(j[k]) for k in ("fx", "fy", "cx", "cy"))
        except KeyError as e:
            fail(cam, "no field %s; expected fx fy cx cy [width height depth_factor]" % e)
        width, height = int(j.get("width", 640)), int(j.get("height", 480))
        depth_factor = float(j.get("depth_factor", depth_factor))
    else:
        fail(args.dataset, "no camera: give --camera fr1|fr2|fr3|FILE.json")
    if args.depth_factor:
        depth_factor = args.depth_factor
    return fx, fy, cx, cy, width, height, depth_factor


def select_motion(frames, min_translation_m=0.05, min_rotation_deg=5.0):
    """objmap's motion keyframes: keep a frame after this much motion since the last kept one."""
    kept, last = [], None
    for f in frames:
        m = f[2]
        if last is not None:
            dt = math.dist([m[i][3] for i in range(3)], [last[i][3] for i in range(3)])
            trace = sum(last[k][i] * m[k][i] for i in range(3) for k in range(3))
            angle = math.degrees(math.acos(max(-1.0, min(1.0, (trace - 1.0) / 2.0))))
            if dt < min_translation_m and angle < min_rotation_deg:
                continue
        kept.append(f)
        last = m
    return kept


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--dataset", required=True, help="TUM RGB-D folder (rgb.txt, depth.txt)")
    p.add_argument("--trajectory", required=True, help="world_from_cam poses, TUM format")
    p.add_argument("--camera", help="fr1|fr2|fr3 or camera.json (default: as objmap fuse)")
    p.add_argument("--depth-factor", type=float, default=0.0, help="depth PNG units per metre")
    p.add_argument("--max-diff", type=float, default=0.02, help="association window, s")
    p.add_argument("--max-depth", type=float, default=4.0, help="farthest depth used, m")
    p.add_argument("--voxel", type=float, default=0.01, help="voxel filter size, m")
    p.add_argument("--nb-neighbors", type=int, default=20, help="outlier filter neighbours")
    p.add_argument("--std-ratio", type=float, default=1.0, help="outlier filter std ratio")
    p.add_argument("--keyframes", choices=["all", "motion"], default="all")
    p.add_argument("--max-frames", type=int, default=0, help="use at most this many frames")
    args = p.parse_args()

    try:
        import numpy as np
        import open3d as o3d
    except ImportError as e:
        fail("python", "%s (install Debian's python3-open3d: scripts/install-deps.sh --bench)" % e)

    t_start = time.perf_counter()
    fx, fy, cx, cy, width, height, depth_factor = camera_for(args)
    rgb = read_list(os.path.join(args.dataset, "rgb.txt"))
    depth = read_list(os.path.join(args.dataset, "depth.txt"))
    traj = read_trajectory(args.trajectory)
    depth_t = [t for t, _ in depth]
    traj_t = [r[0] for r in traj]
    frames, used_depth = [], set()
    for t, rgb_file in rgb:
        d = nearest(depth_t, t, args.max_diff)
        k = nearest(traj_t, t, args.max_diff)
        if d is None or k is None or d in used_depth:
            continue
        used_depth.add(d)
        frames.append((rgb_file, depth[d][1], pose_matrix(*traj[k][1:])))
    if args.keyframes == "motion":
        frames = select_motion(frames)
    if args.max_frames > 0:
        frames = frames[: args.max_frames]
    if not frames:
        fail(args.trajectory, "no frame of %s has a depth image and a pose" % args.dataset)

    intrinsic = o3d.camera.PinholeCameraIntrinsic(width, height, fx, fy, cx, cy)
    cloud = o3d.geometry.PointCloud()
    back_projected = 0
    for rgb_file, depth_file, world_from_cam in frames:
        color = o3d.io.read_image(os.path.join(args.dataset, rgb_file))
        depth_img = o3d.io.read_image(os.path.join(args.dataset, depth_file))
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            color, depth_img, depth_scale=depth_factor, depth_trunc=args.max_depth,
            convert_rgb_to_intensity=False)
        # extrinsic = cam_from_world
        pcd = o3d.geometry.PointCloud.create_from_rgbd_image(
            rgbd, intrinsic, np.linalg.inv(np.array(world_from_cam)))
        back_projected += len(pcd.points)
        cloud += pcd
    voxel = cloud.voxel_down_sample(args.voxel)
    final, _ = voxel.remove_statistical_outlier(nb_neighbors=args.nb_neighbors,
                                                std_ratio=args.std_ratio)
    seconds = time.perf_counter() - t_start
    usage = resource.getrusage(resource.RUSAGE_SELF)
    rss_mb = usage.ru_maxrss / 1024.0
    cpu_seconds = usage.ru_utime + usage.ru_stime
    result = {
        "dataset": os.path.abspath(args.dataset),
        "trajectory": os.path.abspath(args.trajectory),
        "open3d": o3d.__version__,
        "frames": len(frames),
        "keyframes": args.keyframes,
        "seconds": round(seconds, 4),
        "ms_per_frame": round(1000.0 * seconds / len(frames), 3),
        "cpu_ms_per_frame": round(1000.0 * cpu_seconds / len(frames), 3),
        "peak_rss_mb": round(rss_mb, 1),
        "points_back_projected": back_projected,
        "points_voxel": len(voxel.points),
        "points_final": len(final.points),
        "voxel_m": args.voxel,
    }
    sys.stderr.write(
        "open3d %s: %d frames, %.2f s, %.1f ms/frame, peak RSS %.1f MB, %d -> %d -> %d points\n"
        % (o3d.__version__, len(frames), seconds, result["ms_per_frame"], rss_mb, back_projected,
           len(voxel.points), len(final.points)))
    print(json.dumps(result))


if __name__ == "__main__":
    main()
