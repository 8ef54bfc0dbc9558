#!/usr/bin/env python3
"""`duet eval-traj` against an independent calculation of the same figures.

The reference follows the TUM RGB-D benchmark's own scripts, re-written here with numpy:
associate.py (greedy association by the smallest time difference), evaluate_ate.py's align()
(Horn's closed form via the SVD of the cross-covariance of the zero-mean positions) and
evaluate_rpe.py's error (inv(inv(G_i) G_j) * inv(P_i) P_j). It shares no code with duet.

Usage: eval_traj_reference.py DUET_CLI DATA_DIR   (exits 77 = skipped when the data is absent)
"""
import json
import os
import subprocess
import sys

import numpy as np


def read_tum(path):
    poses = {}
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            v = [float(x) for x in line.replace(",", " ").split()]
            poses[v[0]] = np.array(v[1:8])
    return poses


def quat_to_matrix(q):  # x y z w
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def to_T(v):
    T = np.eye(4)
    T[:3, :3] = quat_to_matrix(v[3:7])
    T[:3, 3] = v[:3]
    return T


def associate(first, second, offset, max_difference):
    """associate.py: first = ground truth, second = estimate (offset added to the estimate)."""
    first_keys = list(first.keys())
    second_keys = list(second.keys())
    potential = [(abs(a - (b + offset)), a, b) for a in first_keys for b in second_keys
                 if abs(a - (b + offset)) < max_difference]
    potential.sort()
    matches = []
    for diff, a, b in potential:
        if a in first_keys and b in second_keys:
            first_keys.remove(a)
            second_keys.remove(b)
            matches.append((a, b))
    matches.sort(key=lambda m: m[1])
    return matches


def horn_align(model, data):
    """evaluate_ate.py align(): rotation and translation taking model (estimate) onto data (gt)."""
    model_zc = model - model.mean(1, keepdims=True)
    data_zc = data - data.mean(1, keepdims=True)
    W = np.zeros((3, 3))
    for c in range(model.shape[1]):
        W += np.outer(model_zc[:, c], data_zc[:, c])
    U, d, Vh = np.linalg.svd(W.transpose())
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vh) < 0:
        S[2, 2] = -1
    rot = U @ S @ Vh
    trans = data.mean(1, keepdims=True) - rot @ model.mean(1, keepdims=True)
    err = np.sqrt(((rot @ model + trans - data) ** 2).sum(0))
    return err


def main():
    cli, data = sys.argv[1], sys.argv[2]
    gt_file = os.path.join(data, "trajectories/freiburg1_xyz-groundtruth.txt")
    est_file = os.path.join(data, "trajectories/freiburg1_xyz-rgbdslam.txt")
    if not (os.path.exists(gt_file) and os.path.exists(est_file)):
        print("real trajectories absent: skipped")
        return 77
    gt, est = read_tum(gt_file), read_tum(est_file)
    matches = associate(gt, est, 0.0, 0.02)
    G = np.array([gt[a][:3] for a, b in matches]).T
    P = np.array([est[b][:3] for a, b in matches]).T
    ate = horn_align(P, G)
    # RPE, 1 frame, over the associated pairs in the estimate's order.
    te, re = [], []
    for k in range(len(matches) - 1):
        (a0, b0), (a1, b1) = matches[k], matches[k + 1]
        Gd = np.linalg.inv(to_T(gt[a0])) @ to_T(gt[a1])
        Pd = np.linalg.inv(to_T(est[b0])) @ to_T(est[b1])
        E = np.linalg.inv(Gd) @ Pd
        te.append(np.linalg.norm(E[:3, 3]))
        re.append(np.degrees(np.arccos(min(1.0, max(-1.0, (np.trace(E[:3, :3]) - 1) / 2)))))
    te, re = np.array(te), np.array(re)

    out = subprocess.run([cli, "eval-traj", est_file, gt_file, "--json"], check=True, capture_output=True, text=True).stdout
    j = json.loads(out)
    failures = []

    def check(name, got, want, tol):
        ok = abs(got - want) <= tol
        print(f"{'ok  ' if ok else 'FAIL'} {name}: duet {got:.9f}  reference {want:.9f}")
        if not ok:
            failures.append(name)

    check("pairs", j["association"]["pairs"], len(matches), 0)
    check("ATE rmse [m]", j["ate_m"]["rmse"], float(np.sqrt((ate ** 2).mean())), 1e-9)
    check("ATE mean [m]", j["ate_m"]["mean"], float(ate.mean()), 1e-9)
    check("ATE median [m]", j["ate_m"]["median"], float(np.median(ate)), 1e-9)
    check("ATE std [m]", j["ate_m"]["std"], float(ate.std()), 1e-9)
    check("ATE max [m]", j["ate_m"]["max"], float(ate.max()), 1e-9)
    check("RPE pairs", j["rpe"]["pairs"], len(te), 0)
    check("RPE trans rmse [m]", j["rpe"]["translation_m"]["rmse"], float(np.sqrt((te ** 2).mean())), 1e-9)
    check("RPE trans max [m]", j["rpe"]["translation_m"]["max"], float(te.max()), 1e-9)
    check("RPE rot rmse [deg]", j["rpe"]["rotation_deg"]["rmse"], float(np.sqrt((re ** 2).mean())), 1e-6)
    check("RPE rot mean [deg]", j["rpe"]["rotation_deg"]["mean"], float(re.mean()), 1e-6)
    # Sanity: a real RGB-D SLAM estimate of fr1/xyz is centimetre-accurate (TUM's published
    # RGB-D SLAM results on fr1/xyz are about 1-2 cm ATE RMSE).
    if not (0.003 < j["ate_m"]["rmse"] < 0.05):
        failures.append("ATE rmse outside the plausible 3 mm - 5 cm")
    # The same trajectory against itself: zero error, not aligned.
    same = json.loads(subprocess.run([cli, "eval-traj", gt_file, gt_file, "--json", "--no-align"], check=True,
                                     capture_output=True, text=True).stdout)
    check("self ATE rmse", same["ate_m"]["rmse"], 0.0, 1e-12)
    check("self RPE trans rmse", same["rpe"]["translation_m"]["rmse"], 0.0, 1e-12)
    if failures:
        print("failed:", ", ".join(failures))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
