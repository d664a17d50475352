#!/usr/bin/python3
"""Turn MakeHuman's CC0 base human (hm08) into an SMPL-format body model (sflsh's HDF5 layout).

    /usr/bin/python3 data_tools/makehuman_to_smpl.py ../shared/data/makehuman mh.h5 \
        [--target-betas mh_targets.csv] [--report mh_report.json]

Needs only numpy, scipy and h5py (Debian: python3-numpy python3-scipy python3-h5py). The input
folder holds base.obj, default.mhskel, default_weights.mhw and targets/ (see its README).

What the model file holds (layout: include/sflsh/body/body_model_io.hpp):

* Skin (/v_template, /f): the `body` group of base.obj only (vertices 0..13379; eyes, teeth,
  tongue, helper clothes and the `joint-*` marker cubes are dropped), in metres (x 0.1: the
  file is in decimetres), Y up (as MakeHuman), the MakeHuman origin kept (y = 0 is near the hip
  joints; feet at y = -0.82 m), rest pose as MakeHuman's (an A-pose: arms ~50 deg down,
  elbows slightly bent). Every quad is split along its shorter diagonal.
  Holes: hm08's body group is already watertight (every edge has two faces, genus 0): the eye
  openings are closed by the eyelids' inner lining of the socket and the mouth by the closed
  cavity behind the lips, so there is nothing to fill in this data. The converter still checks
  it: any boundary loop (e.g. from a modified base mesh) is closed by a fan around a new vertex
  at the loop's centroid (skinning weights, shape offsets and regressor support taken as the
  loop's average), and the result must be closed and 2-manifold or the conversion fails.
  Self-intersection is checked by the C++ reader side (`sflsh body info --model`, CGAL).
* Joints: SMPL's 24, each the centre (mean of vertices) of the MakeHuman joint groups listed in
  JOINT_MAP below; /J_regressor is a sparse non-negative regressor over surface vertices (each
  joint: the nearest body vertices in each of 26 directions around it, weights from non-negative least squares on the rest
  joint and the joints of every target body, rows summing to 1), so it reproduces those centres
  at rest (error printed; checked <= 1 cm) and follows them under shape.
* LBS weights (/weights): MakeHuman's 139 weighted bones summed into the 24 SMPL joints by
  BONE_MAP (a bone not listed takes its parent's joint), rows normalised to sum 1.
* Shape directions (/shapedirs, names in /shape_meanings): SHAPE_DIRECTIONS below, 10
  directions built from the targets as offsets from the average (base) body; beta = 0 is the
  base mesh exactly. The data holds only the `universal` gender x muscle x weight targets
  (relative to each gender's young average body; both *-averagemuscle-averageweight targets are
  empty) and the height targets; it has no gender, age or proportion targets
  (macrodetails/*, e.g. female-young.target), so there is no male<->female direction: the
  gender appears only as how the weight/muscle/height changes differ between the female and
  male targets.
* Pose blend shapes: none; /posedirs is stored all zero (the format requires the array).

--target-betas CSV writes, for each target the shape space reproduces exactly (the 8 single-slider
universal targets and the 4 height targets), its beta vector as a `precompute --batch` CSV
(name,b0..b9); --report gives every target's least-squares betas and relative residual (the 8
muscle x weight corner targets: 50-77 %, betas outside [-3, 3], so they are left out of the CSV). --self-test checks the hole filler on a cube with a hole.
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import smpl_pkl_to_h5  # noqa: E402  (the HDF5 writer shared with the SMPL converter)

FORMAT_VERSION = 1
NUM_JOINTS = 24
NUM_POSE_FEATURES = 207
NUM_BODY_VERTICES = 13380  # hm08: the `body` group is vertices 0..13379
DM_TO_M = 0.1
SMPL_JOINT_NAMES = [
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "left_ankle",
    "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar", "right_collar", "head",
    "left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hand",
    "right_hand"]
SMPL_PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]

# SMPL joint <- MakeHuman joint groups (keys of default.mhskel "joints"; each names the vertex
# list of a `joint-*` marker cube of base.obj). The joint is the mean of the groups' centres.
# "{s}" is L for left_*, R for right_* (MakeHuman's .L is the body's left, at +x, as SMPL's).
JOINT_MAP = {
    "pelvis": ["spine05____head"],          # top of MakeHuman's root bone, between the hips
    "hip": ["upperleg01.{s}____head"],      # hip joint (femoral head)
    "spine1": ["spine03____head"],          # lumbar, 11 cm above the pelvis joint
    "knee": ["lowerleg01.{s}____head"],
    "spine2": ["spine02____head"],          # lower thoracic
    "ankle": ["foot.{s}____head"],
    "spine3": ["spine01____head"],          # upper thoracic (chest)
    # ball of the foot: the five toe bases (metatarsophalangeal joints); foot.L's tail is only the
    # midpoint of the ankle and joint-l-foot-1
    "foot": ["toe1-1.{s}____head", "toe2-1.{s}____head", "toe3-1.{s}____head", "toe4-1.{s}____head",
             "toe5-1.{s}____head"],
    "neck": ["neck01____head"],             # base of the neck
    "collar": ["clavicle.{s}____head"],     # sternal end of the clavicle
    "head": ["head____head"],               # top of the neck (skull base)
    "shoulder": ["upperarm01.{s}____head"],  # glenohumeral joint
    "elbow": ["lowerarm01.{s}____head"],
    "wrist": ["wrist.{s}____head"],
    # the knuckles: the four finger bases (metacarpophalangeal joints)
    "hand": ["finger2-1.{s}____head", "finger3-1.{s}____head", "finger4-1.{s}____head", "finger5-1.{s}____head"],
}

# MakeHuman bone -> SMPL joint whose segment (joint -> its child) the bone lies in. Bones not
# listed inherit their parent's joint (face bones -> head, finger phalanges -> hand, toes -> foot,
# breast -> spine2 via spine02). "{s}" as above.
BONE_MAP = {
    "root": "pelvis", "spine05": "pelvis", "spine04": "pelvis", "pelvis.{s}": "pelvis",
    "spine03": "spine1", "spine02": "spine2", "spine01": "spine3",
    "neck01": "neck", "neck02": "neck", "neck03": "neck", "head": "head",
    "clavicle.{s}": "collar", "shoulder01.{s}": "collar",
    "upperarm01.{s}": "shoulder", "upperarm02.{s}": "shoulder",
    "lowerarm01.{s}": "elbow", "lowerarm02.{s}": "elbow",
    "wrist.{s}": "wrist", "metacarpal1.{s}": "wrist", "metacarpal2.{s}": "wrist", "metacarpal3.{s}": "wrist",
    "metacarpal4.{s}": "wrist",
    "finger1-1.{s}": "hand", "finger2-1.{s}": "hand", "finger3-1.{s}": "hand", "finger4-1.{s}": "hand",
    "finger5-1.{s}": "hand",
    "upperleg01.{s}": "hip", "upperleg02.{s}": "hip",
    "lowerleg01.{s}": "knee", "lowerleg02.{s}": "knee",
    "foot.{s}": "ankle",
    "toe1-1.{s}": "foot", "toe2-1.{s}": "foot", "toe3-1.{s}": "foot", "toe4-1.{s}": "foot", "toe5-1.{s}": "foot",
}

UNIVERSAL = "targets/universal-{g}-young-{m}muscle-{w}weight.target"
HEIGHT = "targets/height-{g}-young-averagemuscle-averageweight-{h}height.target"


def _u(T, g, m, w):
    return T[UNIVERSAL.format(g=g, m=m, w=w)]


def _h(T, g, h):
    return T[HEIGHT.format(g=g, h=h)]


def _both(f):
    """Mean over the two genders of f(gender)."""
    return 0.5 * (f("female") + f("male"))


def _diff(f):
    """Half the female - male difference of f(gender)."""
    return 0.5 * (f("female") - f("male"))


def _wdir(T, g):
    return 0.5 * (_u(T, g, "average", "max") - _u(T, g, "average", "min"))


def _mdir(T, g):
    return 0.5 * (_u(T, g, "max", "average") - _u(T, g, "min", "average"))


def _hdir(T, g):
    return 0.5 * (_h(T, g, "max") - _h(T, g, "min"))


def _wasym(T, g):
    return 0.5 * (_u(T, g, "average", "max") + _u(T, g, "average", "min"))


def _masym(T, g):
    return 0.5 * (_u(T, g, "max", "average") + _u(T, g, "min", "average"))


# Every direction is a third of a combination of target offsets from the average (base) body, so
# beta = 0 is the base mesh and beta = +-3 reaches the end of MakeHuman's slider (as +-3 standard
# deviations in SMPL's shape space): the average-muscle max-weight female target is
# beta0 = beta3 = beta5 = beta7 = 3, the max-height body beta2 = beta9 = 3. Together they
# reproduce exactly the 8 single-slider universal targets and the 4 height targets; the 8
# muscle x weight corner targets only approximately (their interaction is not a direction; see
# --target-betas for each target's least-squares betas and residual). The female and male height
# targets are identical in this data, so height has no gender term. (meaning, builder over T:
# target path -> (#all vertices, 3) offsets in metres)
SHAPE_DIRECTIONS = [
    ("weight: +3 max weight, -3 min weight (MakeHuman slider ends; maxweight - minweight at average "
     "muscle, mean of female and male)", lambda T: _both(lambda g: _wdir(T, g)) / 3),
    ("muscle: +3 max muscle, -3 min muscle (maxmuscle - minmuscle at average weight, mean of female "
     "and male)", lambda T: _both(lambda g: _mdir(T, g)) / 3),
    ("height: +3 max height (+0.72 m at the head), -3 min height (maxheight - minheight)",
     lambda T: _both(lambda g: _hdir(T, g)) / 3),
    ("weight, female (+) vs male (-) form of the weight change", lambda T: _diff(lambda g: _wdir(T, g)) / 3),
    ("muscle, female (+) vs male (-) form of the muscle change", lambda T: _diff(lambda g: _mdir(T, g)) / 3),
    ("weight asymmetry: maxweight + minweight (with weight +-3, +3 here gives the max/min-weight target "
     "itself)", lambda T: _both(lambda g: _wasym(T, g)) / 3),
    ("muscle asymmetry: maxmuscle + minmuscle (with muscle +-3, +3 here gives the max/min-muscle target)",
     lambda T: _both(lambda g: _masym(T, g)) / 3),
    ("weight asymmetry, female (+) vs male (-)", lambda T: _diff(lambda g: _wasym(T, g)) / 3),
    ("muscle asymmetry, female (+) vs male (-)", lambda T: _diff(lambda g: _masym(T, g)) / 3),
    ("height asymmetry: maxheight + minheight (with height +-3, +3 here gives the max/min-height target)",
     lambda T: _both(lambda g: 0.5 * (_h(T, g, "max") + _h(T, g, "min"))) / 3),
]


class ConversionError(Exception):
    pass


# --- reading MakeHuman files -------------------------------------------------------------------

def read_obj(path):
    """All vertices (decimetres) and the faces (0-based, as listed) of each group."""
    verts, groups, group = [], {}, None
    try:
        with open(path) as fh:
            for ln, line in enumerate(fh, 1):
                if line.startswith("v "):
                    parts = line.split()
                    if len(parts) < 4:
                        raise ConversionError(f"{path}:{ln}: vertex line with fewer than 3 coordinates")
                    verts.append([float(x) for x in parts[1:4]])
                elif line.startswith("g "):
                    group = line.split()[1] if len(line.split()) > 1 else ""
                elif line.startswith("f "):
                    groups.setdefault(group, []).append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    except OSError as e:
        raise ConversionError(f"{path}: cannot read ({e.strerror})") from None
    except ValueError as e:
        raise ConversionError(f"{path}: malformed number ({e})") from None
    return np.array(verts, dtype=np.float64), groups


def read_json(path):
    try:
        with open(path) as fh:
            return json.load(fh)
    except OSError as e:
        raise ConversionError(f"{path}: cannot read ({e.strerror})") from None
    except json.JSONDecodeError as e:
        raise ConversionError(f"{path}: not valid JSON ({e})") from None


def read_target(path, num_vertices):
    """Dense (num_vertices, 3) offsets (decimetres) of a sparse `index dx dy dz` target."""
    off = np.zeros((num_vertices, 3))
    try:
        with open(path) as fh:
            for ln, line in enumerate(fh, 1):
                s = line.strip()
                if not s or s.startswith("#"):
                    continue
                parts = s.split()
                if len(parts) != 4:
                    raise ConversionError(f"{path}:{ln}: expected 'index dx dy dz', found {s!r}")
                i = int(parts[0])
                if not 0 <= i < num_vertices:
                    raise ConversionError(f"{path}:{ln}: vertex index {i} outside [0, {num_vertices})")
                off[i] = [float(x) for x in parts[1:]]
    except OSError as e:
        raise ConversionError(f"{path}: cannot read ({e.strerror})") from None
    except ValueError as e:
        raise ConversionError(f"{path}: malformed number ({e})") from None
    return off


# --- surface -------------------------------------------------------------------------------------

def triangulate(quads, V):
    """Triangles of polygons (fan for n > 4), quads split along their shorter diagonal."""
    tris = []
    for f in quads:
        if len(f) == 3:
            tris.append(f)
        elif len(f) == 4:
            a, b, c, d = f
            if np.linalg.norm(V[a] - V[c]) <= np.linalg.norm(V[b] - V[d]):
                tris += [[a, b, c], [a, c, d]]
            else:
                tris += [[a, b, d], [b, c, d]]
        else:
            tris += [[f[0], f[i], f[i + 1]] for i in range(1, len(f) - 1)]
    return np.array(tris, dtype=np.int64)


def boundary_loops(F):
    """Boundary loops (vertex lists, oriented like the missing faces would be) of a triangle mesh."""
    from collections import Counter
    und = Counter()
    for f in F:
        for i in range(3):
            a, b = f[i], f[(i + 1) % 3]
            und[(min(a, b), max(a, b))] += 1
    bad = [e for e, n in und.items() if n > 2]
    if bad:
        raise ConversionError(f"the body surface has {len(bad)} edges shared by more than two faces "
                              f"(first: vertices {bad[0]}), expected a 2-manifold")
    nxt = {}
    for f in F:
        for i in range(3):
            a, b = f[i], f[(i + 1) % 3]
            if und[(min(a, b), max(a, b))] == 1:
                if b in nxt:
                    raise ConversionError(f"boundary vertex {b} starts two boundary edges (a pinched hole)")
                nxt[b] = a  # reversed: the filling faces traverse the edge the other way
    loops, seen = [], set()
    for s in sorted(nxt):
        if s in seen:
            continue
        loop, c = [s], nxt[s]
        seen.add(s)
        while c != s:
            loop.append(c)
            seen.add(c)
            c = nxt[c]
        loops.append(loop)
    return loops


def fill_holes(F, num_vertices):
    """Closes every boundary loop with a fan around a new vertex. Returns the new faces and, per
    new vertex, the loop it averages (its position/weights/offsets are the loop's mean)."""
    loops = boundary_loops(F)
    new_faces, added = [], []
    for loop in loops:
        c = num_vertices + len(added)
        added.append(loop)
        new_faces += [[loop[i], loop[(i + 1) % len(loop)], c] for i in range(len(loop))]
    if new_faces:
        F = np.vstack([F, np.array(new_faces, dtype=np.int64)])
    return F, added


def extend_by_loops(A, added):
    """Rows of A (per vertex) extended by the mean over each added vertex's loop."""
    if not added:
        return A
    return np.concatenate([A, np.stack([A[loop].mean(axis=0) for loop in added])], axis=0)


def check_closed_manifold(F, num_vertices):
    """Raises unless every edge has two faces, traversed in opposite directions, and every vertex's
    fan is one disc."""
    from collections import Counter, defaultdict
    directed = Counter()
    for f in F:
        for i in range(3):
            directed[(f[i], f[(i + 1) % 3])] += 1
    for (a, b), n in directed.items():
        if n != 1 or directed.get((b, a), 0) != 1:
            raise ConversionError(f"edge ({a}, {b}) is not shared by exactly two oppositely oriented faces")
    # Vertex manifoldness: the link (edges opposite the vertex) is one cycle.
    link = defaultdict(dict)
    for f in F:
        for i in range(3):
            link[f[i]][f[(i + 1) % 3]] = f[(i + 2) % 3]
    for v in range(num_vertices):
        ring = link.get(v)
        if not ring:
            raise ConversionError(f"vertex {v} is used by no face")
        start = next(iter(ring))
        c, n = ring[start], 1
        while c != start:
            c, n = ring[c], n + 1
            if n > len(ring):
                break
        if n != len(ring):
            raise ConversionError(f"vertex {v} has a fan of {len(ring)} faces that is not one disc")


def signed_volume(V, F):
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


# --- joints, regressor, weights ------------------------------------------------------------------

def side_expand(name, table):
    """Per SMPL joint name the list of table entries with {s} filled in (L for left_, R for right_)."""
    if name.startswith("left_"):
        return [t.format(s="L") for t in table[name[5:]]]
    if name.startswith("right_"):
        return [t.format(s="R") for t in table[name[6:]]]
    return list(table[name])


def joint_centres(joint_groups, all_verts_m):
    """24 by 3 SMPL joints (metres) and the groups used, from all base.obj vertices (metres)."""
    J, used = np.zeros((NUM_JOINTS, 3)), []
    for j, name in enumerate(SMPL_JOINT_NAMES):
        keys = side_expand(name, JOINT_MAP)
        for k in keys:
            if k not in joint_groups:
                raise ConversionError(f"default.mhskel: joint group '{k}' (for SMPL joint {name}) is missing")
        J[j] = np.mean([all_verts_m[joint_groups[k]].mean(axis=0) for k in keys], axis=0)
        used.append(keys)
    return J, used


def regressor_support(rest, joint, per_direction=3, cos_min=0.8):
    """Body vertices around a joint: in each of the 26 lattice directions, the per_direction
    nearest vertices within a cone (cos >= cos_min) around it, so the support surrounds the joint
    (the plain nearest vertices of a spine joint lie all on the back)."""
    d = rest - joint
    r = np.linalg.norm(d, axis=1)
    u = d / np.maximum(r, 1e-12)[:, None]
    support = set()
    for a in (-1, 0, 1):
        for b in (-1, 0, 1):
            for c in (-1, 0, 1):
                if a == b == c == 0:
                    continue
                dirn = np.array([a, b, c], dtype=float) / np.sqrt(a * a + b * b + c * c)
                inside = np.nonzero(u @ dirn >= cos_min)[0]
                support.update(inside[np.argsort(r[inside])[:per_direction]].tolist())
    return np.array(sorted(support))


def fit_regressor(surface_shapes, joint_shapes):
    """Sparse non-negative 24 by V regressor. surface_shapes: list of (V,3) bodies (first = rest),
    joint_shapes: matching list of (24,3). Each row uses regressor_support() of the rest joint;
    NNLS on the rest joint (weight 10), the other bodies' joints (weight 1), the row sum (weight
    100) and a small ridge towards uniform weights, then the row is rescaled to sum 1."""
    import scipy.optimize
    import scipy.sparse as sp
    rest = surface_shapes[0]
    rows, cols, vals = [], [], []
    for j in range(NUM_JOINTS):
        idx = regressor_support(rest, joint_shapes[0][j])
        blocks, rhs = [], []
        for s, (S, Jj) in enumerate(zip(surface_shapes, joint_shapes)):
            w = 10.0 if s == 0 else 1.0
            blocks.append(w * S[idx].T)
            rhs.append(w * Jj[j])
        blocks.append(100.0 * np.ones((1, len(idx))))
        rhs.append(np.array([100.0]))
        A = np.vstack(blocks + [1e-3 * np.eye(len(idx))])
        b = np.concatenate(rhs + [np.full(len(idx), 1e-3 / len(idx))])
        x, _ = scipy.optimize.nnls(A, b, maxiter=50 * len(idx))
        if x.sum() <= 0:
            raise ConversionError(f"joint regressor: no non-negative fit for joint {SMPL_JOINT_NAMES[j]}")
        keep = x > 1e-6
        x = x[keep] / x[keep].sum()
        rows += [j] * int(keep.sum())
        cols += list(idx[keep])
        vals += list(x)
    return sp.csr_matrix((vals, (rows, cols)), shape=(NUM_JOINTS, rest.shape[0]))


def bone_to_joint(bones):
    """MakeHuman bone name -> SMPL joint index (BONE_MAP, else inherited from the parent)."""
    direct = {}
    for key, target in BONE_MAP.items():
        if "{s}" in key:
            for s, side in (("L", "left_"), ("R", "right_")):
                sided = side + target if side + target in SMPL_JOINT_NAMES else target  # pelvis.L -> pelvis
                direct[key.format(s=s)] = SMPL_JOINT_NAMES.index(sided)
        else:
            direct[key] = SMPL_JOINT_NAMES.index(target)
    out = {}

    def resolve(b, depth=0):
        if b in out:
            return out[b]
        if b in direct:
            out[b] = direct[b]
        elif bones[b].get("parent") is None or depth > 200:
            raise ConversionError(f"default.mhskel: bone '{b}' has no SMPL joint (not in BONE_MAP, no parent)")
        else:
            out[b] = resolve(bones[b]["parent"], depth + 1)
        return out[b]

    for b in bones:
        resolve(b)
    return out


def lbs_weights(weights_json, bones, num_vertices):
    """num_vertices by 24 weights summed from MakeHuman's bones, rows normalised to 1."""
    b2j = bone_to_joint(bones)
    W = np.zeros((num_vertices, NUM_JOINTS))
    for bone, pairs in weights_json.items():
        if bone not in b2j:
            raise ConversionError(f"default_weights.mhw: bone '{bone}' is not in default.mhskel")
        for v, w in pairs:
            if v < num_vertices:
                W[int(v), b2j[bone]] += float(w)
    s = W.sum(axis=1)
    if np.any(s <= 0):
        raise ConversionError(f"default_weights.mhw: {int((s <= 0).sum())} body vertices have no weight "
                              f"(first: {int(np.argmax(s <= 0))})")
    return W / s[:, None], b2j


# --- conversion ----------------------------------------------------------------------------------

def load_targets(folder, num_all):
    T = {}
    for g in ("female", "male"):
        for m in ("min", "average", "max"):
            for w in ("min", "average", "max"):
                T[UNIVERSAL.format(g=g, m=m, w=w)] = None
        for h in ("min", "max"):
            T[HEIGHT.format(g=g, h=h)] = None
    for name in T:
        path = os.path.join(folder, name)
        if not os.path.exists(path):
            raise ConversionError(f"{path}: target file missing (needed by the shape directions)")
        T[name] = read_target(path, num_all) * DM_TO_M
    return T


def convert(folder, out_path, target_betas=None, report_path=None):
    obj = os.path.join(folder, "base.obj")
    all_dm, groups = read_obj(obj)
    if "body" not in groups:
        raise ConversionError(f"{obj}: no group 'body'")
    if all_dm.shape[0] < NUM_BODY_VERTICES:
        raise ConversionError(f"{obj}: {all_dm.shape[0]} vertices, expected at least {NUM_BODY_VERTICES} (hm08)")
    body = groups["body"]
    lo, hi = min(min(f) for f in body), max(max(f) for f in body)
    if lo != 0 or hi != NUM_BODY_VERTICES - 1:
        raise ConversionError(f"{obj}: group 'body' uses vertices {lo}..{hi}, expected 0..{NUM_BODY_VERTICES - 1}")
    all_m = all_dm * DM_TO_M
    V0 = all_m[:NUM_BODY_VERTICES]
    F = triangulate(body, V0)
    F, added = fill_holes(F, NUM_BODY_VERTICES)
    V = extend_by_loops(V0, added)
    check_closed_manifold(F, V.shape[0])
    vol = signed_volume(V, F)
    if vol < 0:
        F = F[:, [0, 2, 1]]
        vol = -vol

    skel = read_json(os.path.join(folder, "default.mhskel"))
    for key in ("bones", "joints"):
        if key not in skel:
            raise ConversionError(f"{folder}/default.mhskel: key '{key}' missing")
    J, used_groups = joint_centres(skel["joints"], all_m)
    mhw = read_json(os.path.join(folder, "default_weights.mhw"))
    if "weights" not in mhw:
        raise ConversionError(f"{folder}/default_weights.mhw: key 'weights' missing")
    W, b2j = lbs_weights(mhw["weights"], skel["bones"], NUM_BODY_VERTICES)
    W = extend_by_loops(W, added)

    T = load_targets(folder, all_m.shape[0])
    dirs = [build(T) for _, build in SHAPE_DIRECTIONS]
    shapedirs = np.stack([extend_by_loops(d[:NUM_BODY_VERTICES], added) for d in dirs], axis=2)

    # Regressor: fitted on the rest body and every non-empty target body (joints from the same
    # groups, moved by the target).
    bodies, joints = [V], [J]
    target_names = [n for n in sorted(T) if np.any(T[n])]
    for n in target_names:
        bodies.append(extend_by_loops(V0 + T[n][:NUM_BODY_VERTICES], added))
        joints.append(joint_centres(skel["joints"], all_m + T[n])[0])
    jr = fit_regressor(bodies, joints)
    rest_err = np.linalg.norm(jr @ V - J, axis=1)
    shape_err = max(float(np.linalg.norm(jr @ B - Jb, axis=1).max()) for B, Jb in zip(bodies[1:], joints[1:]))
    if rest_err.max() > 0.01:
        j = int(np.argmax(rest_err))
        raise ConversionError(f"joint regressor misses joint {SMPL_JOINT_NAMES[j]} by {rest_err[j] * 1e3:.1f} mm "
                              f"(> 10 mm)")

    # Least-squares betas of each target body.
    D = shapedirs.reshape(-1, shapedirs.shape[2])
    rows = []
    for n in target_names:
        off = extend_by_loops(T[n][:NUM_BODY_VERTICES], added).reshape(-1)
        beta, *_ = np.linalg.lstsq(D, off, rcond=None)
        rel = float(np.linalg.norm(D @ beta - off) / max(np.linalg.norm(off), 1e-12))
        rows.append((os.path.basename(n)[:-len(".target")], beta, rel))

    m = {"v_template": V, "f": F.astype(np.int32), "shapedirs": shapedirs,
         "posedirs": np.zeros((V.shape[0], 3, NUM_POSE_FEATURES)), "weights": W,
         "kintree_table": np.array([SMPL_PARENTS, list(range(NUM_JOINTS))], dtype=np.int32), "J_regressor": jr}
    smpl_pkl_to_h5.write_h5(m, out_path, "MakeHuman hm08 base human (CC0) via data_tools/makehuman_to_smpl.py",
                            [meaning for meaning, _ in SHAPE_DIRECTIONS])
    if target_betas:
        write_target_betas(target_betas, rows)
    report = {
        "vertices": int(V.shape[0]), "faces": int(F.shape[0]), "holes_filled": len(added),
        "volume_m3": vol, "height_m": float(V[:, 1].max() - V[:, 1].min()),
        "joints": {SMPL_JOINT_NAMES[j]: {"groups": used_groups[j], "position_m": J[j].tolist(),
                                         "regressor_error_mm": float(rest_err[j] * 1e3)} for j in range(NUM_JOINTS)},
        "regressor_nnz": int(jr.nnz), "regressor_max_error_on_targets_mm": shape_err * 1e3,
        "bone_to_joint": {b: SMPL_JOINT_NAMES[j] for b, j in sorted(b2j.items())},
        "target_betas": {n: {"betas": b.tolist(), "relative_residual": r} for n, b, r in rows},
    }
    if report_path:
        with open(report_path, "w") as fh:
            json.dump(report, fh, indent=1)
    print(f"{out_path}: {V.shape[0]} vertices, {F.shape[0]} triangles, {len(added)} holes filled, "
          f"height {report['height_m']:.3f} m, volume {vol:.4f} m^3, {shapedirs.shape[2]} shape directions, "
          f"J_regressor {jr.nnz} non-zeros (rest error max {rest_err.max() * 1e3:.3f} mm, on the "
          f"{len(target_names)} target bodies {shape_err * 1e3:.2f} mm)")
    return report


def write_target_betas(path, rows):
    tmp = path + ".partial"
    with open(tmp, "w") as fh:
        fh.write("name," + ",".join(f"b{i}" for i in range(len(SHAPE_DIRECTIONS))) + "\n")
        for name, beta, rel in rows:
            if rel > 1e-6:
                continue  # not in the shape space (a muscle x weight corner): least squares would extrapolate
            fh.write(name + "," + ",".join(f"{b:.6f}" for b in beta) + "\n")
    os.replace(tmp, path)


def self_test():
    """The hole filler on a cube (12 triangles) with two faces (one square side) removed."""
    V = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    F = triangulate(quads, V)
    check_closed_manifold(F, 8)
    assert abs(abs(signed_volume(V, F)) - 1.0) < 1e-12
    open_F = F[2:]  # the side x = 0 (quad 0) removed
    assert len(boundary_loops(open_F)) == 1
    closed, added = fill_holes(open_F, 8)
    V2 = extend_by_loops(V, added)
    check_closed_manifold(closed, 9)
    assert np.allclose(V2[8], [0, 0.5, 0.5]), V2[8]
    assert abs(signed_volume(V2, closed) - signed_volume(V, F)) < 1e-12, "the fan must close the cube exactly"
    try:
        check_closed_manifold(open_F, 8)
        raise AssertionError("an open surface passed the closedness check")
    except ConversionError:
        pass
    print("self-test passed")


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder", nargs="?", help="MakeHuman data folder (base.obj, default.mhskel, ...)")
    ap.add_argument("output", nargs="?", help="output .h5")
    ap.add_argument("--target-betas", metavar="CSV", help="write each target's least-squares betas")
    ap.add_argument("--report", metavar="JSON", help="write the joint table, errors and bone map")
    ap.add_argument("--self-test", action="store_true")
    args = ap.parse_args(argv)
    try:
        if args.self_test:
            self_test()
        elif args.folder and args.output:
            convert(args.folder, args.output, args.target_betas, args.report)
        else:
            ap.error("give FOLDER and OUTPUT (or --self-test)")
    except ConversionError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
