#!/usr/bin/env python3
"""Open3D dense RGB-D SLAM peer for bench/slam_bench (Debian's python3-open3d 0.16, CPU build).

What runs (Debian's Open3D has no IPP: t.pipelines.slam.Model.track_frame_to_model and the
t.pipelines.odometry functions throw in Image::FilterBilateral on the CPU device, so the
peer's frame-to-model tracking is assembled from the parts that work):
  1. integration: open3d.t.pipelines.slam.Model.integrate (voxel-block TSDF, 16^3 blocks),
     voxel size, truncation (in voxels) and depth range as emf's;
  2. ray casting: Model.synthesize_model_frame at the previous pose (depth of the model);
  3. tracking: open3d.pipelines.registration.registration_icp (legacy, KD-tree; the tensor
     t.pipelines.registration.icp takes ~30 s per call here), point-to-plane, of the frame's
     point cloud
     (depth pixels at --source-stride) against the ray-cast model's points (every
     --target-stride-th pixel) with normals from the ray-cast vertex map (cross product of
     neighbour differences), starting from the constant-velocity prediction; coarse-to-fine
     correspondence distances (--icp-distances), --icp-iterations per level.
Timing per frame covers 2 + 3 + 1 (images are loaded before the clock starts).
Writes <out>/camera.txt (TUM, T_world_camera; world = first camera) and <out>/peer.json
(ms per frame list, peak RSS, what ran).
"""
import argparse
import json
import os
import resource
import sys
import time

import numpy as np


def read_list(path):
    rows = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith("#"):
                rows.append(line.split())
    return rows


def quat_from_matrix(R):
    # Shepperd's method; returns x, y, z, w with w >= 0.
    t = np.trace(R)
    if t > 0:
        s = np.sqrt(t + 1.0) * 2
        w, x, y, z = 0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = np.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2]) * 2
        w, x, y, z = (R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s
    elif R[1, 1] > R[2, 2]:
        s = np.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2]) * 2
        w, x, y, z = (R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s
    else:
        s = np.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1]) * 2
        w, x, y, z = (R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s
    q = np.array([x, y, z, w])
    return -q if w < 0 else q


def model_points(depth_m, K, stride):
    """Camera-frame points and normals of a ray-cast depth image (metres, 0 = none)."""
    h, w = depth_m.shape
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    u = np.arange(w, dtype=np.float32)[None, :]
    v = np.arange(h, dtype=np.float32)[:, None]
    z = depth_m
    P = np.stack([(u - cx) / fx * z, (v - cy) / fy * z, z], axis=-1)
    dx = P[1:-1, 2:] - P[1:-1, :-2]
    dy = P[2:, 1:-1] - P[:-2, 1:-1]
    n = np.cross(dx, dy)
    norm = np.linalg.norm(n, axis=-1)
    ok = (z[1:-1, 1:-1] > 0) & (z[1:-1, 2:] > 0) & (z[1:-1, :-2] > 0) & (z[2:, 1:-1] > 0) & (
        z[:-2, 1:-1] > 0) & (norm > 0)
    # Reject normals across depth discontinuities (neighbour gaps > 5 cm).
    ok &= (np.abs(dx[..., 2]) < 0.05) & (np.abs(dy[..., 2]) < 0.05)
    sel = np.zeros_like(ok)
    sel[::stride, ::stride] = True
    ok &= sel
    pts = P[1:-1, 1:-1][ok]
    nrm = n[ok] / norm[ok][:, None]
    # Normals point towards the camera.
    flip = np.sum(nrm * pts, axis=1) > 0
    nrm[flip] *= -1
    return pts.astype(np.float32), nrm.astype(np.float32)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True, help="TUM folder (associations.txt, calibration.txt)")
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--depth-scale", type=float, default=5000.0, help="uint16 depth units per metre")
    ap.add_argument("--voxel", type=float, default=0.01, help="voxel size, m")
    ap.add_argument("--trunc-voxels", type=float, default=10.0, help="truncation, voxels")
    ap.add_argument("--depth-min", type=float, default=0.1, help="m")
    ap.add_argument("--depth-max", type=float, default=5.0, help="m")
    ap.add_argument("--frames", type=int, default=0, help="0 = all")
    ap.add_argument("--block-count", type=int, default=40000, help="voxel blocks (16^3) reserved")
    ap.add_argument("--source-stride", type=int, default=2, help="frame pixels used by ICP")
    ap.add_argument("--target-stride", type=int, default=2, help="ray-cast pixels used by ICP")
    ap.add_argument("--icp-distances", default="0.08,0.04,0.02", help="m per level")
    ap.add_argument("--icp-iterations", type=int, default=10, help="per level")
    a = ap.parse_args()

    import open3d as o3d
    import open3d.core as o3c
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    T = o3d.t
    dev = o3c.Device("CPU:0")
    cal = [float(x) for x in open(os.path.join(a.data, "calibration.txt")).read().split()]
    fx, fy, cx, cy, width, height = cal[0], cal[1], cal[2], cal[3], int(cal[4]), int(cal[5])
    K = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1]], dtype=np.float64)
    Kt = o3c.Tensor(K)
    rows = read_list(os.path.join(a.data, "associations.txt"))
    if a.frames > 0:
        rows = rows[: a.frames]
    if not rows:
        sys.exit(f"{a.data}/associations.txt: no frames")
    # Load every frame first (not timed).
    frames = []
    for r in rows:
        depth = T.io.read_image(os.path.join(a.data, r[3]))
        color = T.io.read_image(os.path.join(a.data, r[1]))
        frames.append((r[2], depth, color))

    model = T.pipelines.slam.Model(a.voxel, 16, a.block_count, o3c.Tensor(np.eye(4)), dev)
    inp = T.pipelines.slam.Frame(height, width, Kt, dev)
    ray = T.pipelines.slam.Frame(height, width, Kt, dev)
    reg = o3d.pipelines.registration
    dists = [float(x) for x in a.icp_distances.split(",")]
    crit = reg.ICPConvergenceCriteria(1e-6, 1e-6, a.icp_iterations)
    est = reg.TransformationEstimationPointToPlane()
    poses, ms, fitness = [], [], []
    T_world_cam = np.eye(4)
    motion = np.eye(4)
    for i, (stamp, depth, color) in enumerate(frames):
        t0 = time.perf_counter()
        inp.set_data_from_image("depth", depth)
        inp.set_data_from_image("color", color)
        if i > 0:
            model.update_frame_pose(i - 1, o3c.Tensor(T_world_cam))
            model.synthesize_model_frame(ray, a.depth_scale, a.depth_min, a.depth_max,
                                         a.trunc_voxels, False)
            rd = ray.get_data_as_image("depth").as_tensor().numpy()[:, :, 0] / a.depth_scale
            tp, tn = model_points(rd, K, a.target_stride)
            tgt = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(tp.astype(np.float64)))
            tgt.normals = o3d.utility.Vector3dVector(tn.astype(np.float64))
            src_t = T.geometry.PointCloud.create_from_depth_image(
                depth, Kt, o3c.Tensor(np.eye(4)), a.depth_scale, a.depth_max, a.source_stride)
            sp = src_t.point.positions.numpy()
            sp = sp[sp[:, 2] >= a.depth_min]
            src = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(sp.astype(np.float64)))
            init = motion  # T_prev_cur prediction (constant velocity)
            for d in dists:
                r = reg.registration_icp(src, tgt, d, init, est, crit)
                init = np.asarray(r.transformation)
            fitness.append(float(r.fitness))
            T_new = T_world_cam @ init
            motion = np.linalg.inv(T_world_cam) @ T_new
            T_world_cam = T_new
        model.update_frame_pose(i, o3c.Tensor(T_world_cam))
        model.integrate(inp, a.depth_scale, a.depth_max, a.trunc_voxels)
        ms.append((time.perf_counter() - t0) * 1000.0)
        poses.append((stamp, T_world_cam.copy()))

    os.makedirs(a.out, exist_ok=True)
    tmp = os.path.join(a.out, "camera.txt.tmp")
    with open(tmp, "w") as f:
        f.write("# Open3D peer T_world_camera: timestamp tx ty tz qx qy qz qw\n")
        for stamp, P in poses:
            q = quat_from_matrix(P[:3, :3])
            f.write("%s %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n" % (stamp, *P[:3, 3], *q))
    os.replace(tmp, os.path.join(a.out, "camera.txt"))
    ru = resource.getrusage(resource.RUSAGE_SELF)
    info = {
        "ran": "open3d %s: t.pipelines.slam.Model integrate + synthesize_model_frame (ray cast); "
               "tracking = pipelines.registration.registration_icp (legacy) point-to-plane, frame cloud (stride %d) vs "
               "ray-cast model cloud (stride %d, normals from the vertex map), distances %s m, "
               "%d iterations per level, constant-velocity init" %
               (o3d.__version__, a.source_stride, a.target_stride, a.icp_distances, a.icp_iterations),
        "frames": len(frames),
        "ms_per_frame": ms,
        "peak_rss_kb": ru.ru_maxrss,
        "icp_fitness_min": min(fitness) if fitness else None,
        "voxel_m": a.voxel, "trunc_voxels": a.trunc_voxels,
        "depth_min_m": a.depth_min, "depth_max_m": a.depth_max,
    }
    tmp = os.path.join(a.out, "peer.json.tmp")
    with open(tmp, "w") as f:
        json.dump(info, f, indent=1)
    os.replace(tmp, os.path.join(a.out, "peer.json"))
    print("open3d peer: %d frames, %.1f ms/frame median" % (len(ms), float(np.median(ms))))


if __name__ == "__main__":
    main()
