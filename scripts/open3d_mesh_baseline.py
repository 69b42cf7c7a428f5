#!/usr/bin/env python3
"""The mesh job of `objmap fuse --mesh` done with Open3D's ScalableTSDFVolume, for docs/mesh.md.

Takes an objmap fuse run (its run.json names the recording, the trajectory and the camera) and
writes a copy of it to --out whose meshes are Open3D's, so that `objmap eval surface` scores both the
same way:
  --objects: each object of objects.json gets a ScalableTSDFVolume (objmap's voxel for it, sdf_trunc
    max(3 voxels, 1 cm)) fused from the frames that observed it, with the depth masked by its label
    in the run's PNG label masks (value = class id, masks/classes.txt; ycbv_0000_10f), and meshed
    (objects/<id>_<class>_mesh.ply);
  --scene: one ScalableTSDFVolume (--scene-voxel, sdf_trunc 3 voxels) of every motion keyframe's
    whole depth, meshed (map_mesh.ply).
Prints one JSON line on stdout: seconds, cpu_seconds, peak_rss_mb, triangles, open3d version.
Needs Debian's python3-open3d.

  /usr/bin/python3 scripts/open3d_mesh_baseline.py --run RUN --out RUN_O3D --objects|--scene
"""
import argparse
import json
import os
import resource
import shutil
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from open3d_baseline import pose_matrix, select_motion  # noqa: E402
from tum import fail, nearest, read_list, read_trajectory  # noqa: E402


def frames_of(dataset, trajectory, max_diff=0.02):
    """(timestamp, rgb file, depth file, world_from_cam) of every frame with depth and a pose."""
    rgb = read_list(os.path.join(dataset, "rgb.txt"))
    depth = read_list(os.path.join(dataset, "depth.txt"))
    traj = read_trajectory(trajectory)
    depth_t, traj_t = [t for t, _ in depth], [r[0] for r in traj]
    out = []
    for t, rgb_file in rgb:
        d, k = nearest(depth_t, t, max_diff), nearest(traj_t, t, max_diff)
        if d is not None and k is not None:
            out.append((t, rgb_file, depth[d][1], pose_matrix(*traj[k][1:])))
    return out


def class_ids(masks):
    ids = {}
    with open(os.path.join(masks, "classes.txt")) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                value, name = line.split()[:2]
                ids[name.replace("_", " ")] = int(value)
    return ids


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--run", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--objects", action="store_true")
    p.add_argument("--scene", action="store_true")
    p.add_argument("--scene-voxel", type=float, default=0.02)
    p.add_argument("--max-depth", type=float, default=4.0)
    args = p.parse_args()
    try:
        import numpy as np
        import open3d as o3d
    except ImportError as e:
        fail("python", "%s (install Debian's python3-open3d)" % e)
    run = json.load(open(os.path.join(args.run, "run.json")))
    objects = json.load(open(os.path.join(args.run, "objects.json")))["objects"]
    inputs, cam = run["inputs"], run["inputs"]["camera"]
    dataset = inputs["dataset"]["path"]
    frames = frames_of(dataset, inputs["trajectory"]["path"])
    intrinsic = o3d.camera.PinholeCameraIntrinsic(cam["width"], cam["height"], cam["fx"], cam["fy"],
                                                  cam["cx"], cam["cy"])
    scale = cam["depth_factor"]
    if os.path.exists(args.out):
        shutil.rmtree(args.out)
    shutil.copytree(args.run, args.out)
    t0, c0 = time.perf_counter(), time.process_time()
    triangles = 0

    def rgbd(frame, mask=None):
        color = o3d.io.read_image(os.path.join(dataset, frame[1]))
        depth = np.asarray(o3d.io.read_image(os.path.join(dataset, frame[2]))).copy()
        if mask is not None:
            depth[~mask] = 0
        return o3d.geometry.RGBDImage.create_from_color_and_depth(
            color, o3d.geometry.Image(depth), depth_scale=scale, depth_trunc=args.max_depth,
            convert_rgb_to_intensity=False)

    if args.objects:
        masks = inputs["segmentation"]["path"]
        ids = class_ids(masks)
        for o in objects:
            if not o.get("mesh") or o["class"] not in ids:
                continue
            voxel = o["mesh"]["voxel_m"]
            volume = o3d.pipelines.integration.ScalableTSDFVolume(
                voxel_length=voxel, sdf_trunc=max(3 * voxel, 0.01),
                color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8)
            stamps = {round(obs["timestamp"], 6) for obs in o["observations"]}
            for f in frames:
                if round(f[0], 6) not in stamps:
                    continue
                label = np.asarray(o3d.io.read_image(os.path.join(masks, "%.6f.png" % f[0])))
                volume.integrate(rgbd(f, label == ids[o["class"]]), intrinsic,
                                 np.linalg.inv(np.array(f[3])))
            mesh = volume.extract_triangle_mesh()
            mesh.compute_vertex_normals()
            triangles += len(mesh.triangles)
            name = os.path.splitext(o["ply"])[0] + "_mesh.ply"
            o3d.io.write_triangle_mesh(os.path.join(args.out, name), mesh)
    if args.scene:
        volume = o3d.pipelines.integration.ScalableTSDFVolume(
            voxel_length=args.scene_voxel, sdf_trunc=3 * args.scene_voxel,
            color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8)
        keyframes = select_motion([(f[1], f[2], f[3], f) for f in frames])
        for k in keyframes:
            volume.integrate(rgbd(k[3]), intrinsic, np.linalg.inv(np.array(k[3][3])))
        mesh = volume.extract_triangle_mesh()
        mesh.compute_vertex_normals()
        triangles += len(mesh.triangles)
        o3d.io.write_triangle_mesh(os.path.join(args.out, "map_mesh.ply"), mesh)
    print(json.dumps({"seconds": time.perf_counter() - t0, "cpu_seconds": time.process_time() - c0,
                      "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
                      "triangles": triangles, "open3d": o3d.__version__}))


if __name__ == "__main__":
    main()
