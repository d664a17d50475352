#!/usr/bin/python3
"""Pure-numpy SMPL forward function and the generator of sflsh's SMPL test fixtures.

Written from the SMPL paper (Loper, Mahmood, Romero, Pons-Moll, Black, "SMPL: A
Skinned Multi-Person Linear Model", SIGGRAPH Asia 2015), independently of the
C++ code it checks:

    v_shaped  = T + sum_b beta_b S_b                         (eq. 8)
    J         = Jreg v_shaped                                (eq. 10)
    v_unposed = v_shaped + P vec(R_j(theta) - I), j = 1..23  (eq. 9, row-major)
    G_j       = G_parent(j) [R_j | J_j - J_parent(j)]         (eq. 4)
    v_posed   = sum_j w_j G_j [I | -J_j] v_unposed + trans   (eqs. 2-3)

Usage:
    /usr/bin/python3 data_tools/smpl_reference.py make-fixtures OUT_DIR   (the build: build/test_data)
        writes tiny_smpl.npz (a random 20-vertex SMPL-format model, float32,
        compressed) and tiny_smpl_expected.npz (float64 reference outputs).
    /usr/bin/python3 data_tools/smpl_reference.py pose MODEL.npz [--betas 0.5,-1]
        prints the shaped height and the posed joints of a model (a quick look).
"""
import argparse
import os
import sys

import numpy as np

NUM_JOINTS = 24
NUM_POSE_FEATURES = 9 * (NUM_JOINTS - 1)
SMPL_PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]


def rodrigues(r):
    """3x3 rotation of the axis-angle vector r (radians)."""
    r = np.asarray(r, dtype=np.float64)
    theta = np.linalg.norm(r)
    if theta < 1e-12:
        k = np.zeros(3)
        theta = 0.0
    else:
        k = r / theta
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(theta) * K + (1.0 - np.cos(theta)) * (K @ K)


def load_model(path):
    """SMPL arrays of an .npz model as float64, parents with -1 for the root."""
    with np.load(path, allow_pickle=False) as z:
        m = {k: np.array(z[k]) for k in ("v_template", "f", "shapedirs", "posedirs", "J_regressor", "weights",
                                          "kintree_table")}
    for k in ("v_template", "shapedirs", "posedirs", "J_regressor", "weights"):
        m[k] = m[k].astype(np.float64)
    parents = m["kintree_table"][0].astype(np.int64)
    parents[0] = -1
    m["parents"] = parents
    return m


def forward(m, betas, pose, trans):
    """SMPL forward: returns dict v_shaped, joints_rest, v_posed, joints_posed."""
    betas = np.asarray(betas, dtype=np.float64)
    pose = np.asarray(pose, dtype=np.float64).reshape(NUM_JOINTS, 3)
    trans = np.asarray(trans, dtype=np.float64)
    B = betas.shape[0]
    v_shaped = m["v_template"] + np.einsum("vcb,b->vc", m["shapedirs"][:, :, :B], betas)
    J = m["J_regressor"] @ v_shaped
    R = np.stack([rodrigues(p) for p in pose])
    feature = (R[1:] - np.eye(3)).reshape(-1)  # row-major ravel per joint, joints 1..23
    v_unposed = v_shaped + np.einsum("vcp,p->vc", m["posedirs"], feature)

    G = np.zeros((NUM_JOINTS, 4, 4))
    for j in range(NUM_JOINTS):
        local = np.eye(4)
        local[:3, :3] = R[j]
        p = m["parents"][j]
        local[:3, 3] = J[j] - (J[p] if p >= 0 else 0.0)
        G[j] = local if p < 0 else G[p] @ local
    joints_posed = G[:, :3, 3] + trans
    A = G.copy()
    A[:, :3, 3] -= np.einsum("jab,jb->ja", G[:, :3, :3], J)
    T = np.einsum("vj,jab->vab", m["weights"], A)
    v_posed = np.einsum("vab,vb->va", T[:, :3, :3], v_unposed) + T[:, :3, 3] + trans
    return {"v_shaped": v_shaped, "joints_rest": J, "v_posed": v_posed, "joints_posed": joints_posed}


def make_tiny_model(rng, V=20, B=4):
    """A random SMPL-format model: every array non-trivial, weights and
    regressor rows convex combinations, SMPL's kintree_table encoding."""
    v_template = rng.uniform(-0.5, 0.5, size=(V, 3)) + np.array([0.0, 1.0, 0.0])
    f = np.stack([rng.choice(V, size=3, replace=False) for _ in range(30)]).astype(np.uint32)
    shapedirs = rng.normal(scale=0.02, size=(V, 3, B))
    # About a third of the pose directions non-zero: exercised, yet the
    # committed fixture stays small (zeros compress).
    posedirs = rng.normal(scale=0.01, size=(V, 3, NUM_POSE_FEATURES)) * (rng.uniform(size=(V, 3, NUM_POSE_FEATURES)) < 0.3)
    J_regressor = np.zeros((NUM_JOINTS, V))
    for j in range(NUM_JOINTS):
        cols = rng.choice(V, size=rng.integers(2, 5), replace=False)
        w = rng.uniform(0.1, 1.0, size=cols.size)
        J_regressor[j, cols] = w / w.sum()
    weights = np.zeros((V, NUM_JOINTS))
    for v in range(V):
        cols = rng.choice(NUM_JOINTS, size=rng.integers(1, 5), replace=False)
        w = rng.uniform(0.1, 1.0, size=cols.size)
        weights[v, cols] = w / w.sum()
    kintree_table = np.array([SMPL_PARENTS, list(range(NUM_JOINTS))], dtype=np.int64)
    kintree_table[0, 0] = 4294967295  # how SMPL's files mark the root
    f32 = np.float32
    return {
        "v_template": v_template.astype(f32),
        "f": f,
        # Fortran order on purpose: the C++ reader must transpose it.
        "shapedirs": np.asfortranarray(shapedirs.astype(f32)),
        "posedirs": posedirs.astype(f32),
        "J_regressor": J_regressor.astype(f32),
        "weights": weights.astype(f32),
        "kintree_table": kintree_table,
        # Extra entries real files carry: a 0-d unicode array and an object array (skipped by readers).
        "gender": np.array("neutral"),
        "bs_style": np.array({"style": "lbs"}, dtype=object),
    }


def make_fixtures(out_dir):
    rng = np.random.default_rng(20240615)
    model = make_tiny_model(rng)
    model_path = os.path.join(out_dir, "tiny_smpl.npz")
    np.savez_compressed(model_path, **model)
    m = load_model(model_path)  # the float32 values, exactly as the C++ side reads them

    cases = [
        (np.zeros(4), np.zeros((NUM_JOINTS, 3)), np.zeros(3)),
        (rng.normal(size=4), rng.normal(scale=0.5, size=(NUM_JOINTS, 3)), np.array([0.1, -0.2, 0.3])),
        # Fewer betas than the model has, near-pi and exactly-zero rotations.
        (np.array([1.5, -2.0]), np.vstack([rng.normal(size=(23, 3)) * 1.0, np.zeros((1, 3))]), np.array([1.0, 0, 0])),
    ]
    cases[2][1][5] = np.array([0.0, 3.1, 0.0])
    out = {"num_cases": np.array(len(cases))}
    for i, (betas, pose, trans) in enumerate(cases):
        r = forward(m, betas, pose, trans)
        out[f"case{i}_betas"] = betas
        out[f"case{i}_pose"] = pose
        out[f"case{i}_trans"] = trans
        for k, v in r.items():
            out[f"case{i}_{k}"] = v
    np.savez(os.path.join(out_dir, "tiny_smpl_expected.npz"), **out)  # stored (uncompressed) entries
    print(f"wrote {model_path} and tiny_smpl_expected.npz ({len(cases)} cases) to {out_dir}")


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    mk = sub.add_parser("make-fixtures", help="write tiny_smpl.npz and tiny_smpl_expected.npz")
    mk.add_argument("out_dir")
    po = sub.add_parser("pose", help="print shaped height and posed joints of an .npz model")
    po.add_argument("model")
    po.add_argument("--betas", default="")
    args = ap.parse_args(argv)
    if args.cmd == "make-fixtures":
        make_fixtures(args.out_dir)
    else:
        m = load_model(args.model)
        betas = [float(t) for t in args.betas.split(",")] if args.betas else []
        r = forward(m, betas, np.zeros((NUM_JOINTS, 3)), np.zeros(3))
        print("height (m):", np.ptp(r["v_shaped"][:, 1]))
        np.set_printoptions(precision=4, suppress=True)
        print("joints:\n", r["joints_posed"])


if __name__ == "__main__":
    main(sys.argv[1:])
