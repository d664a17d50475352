#!/usr/bin/python3
"""Convert an SMPL model (.pkl as distributed, or .npz) into sflsh's HDF5 body-model layout.

    /usr/bin/python3 data_tools/smpl_pkl_to_h5.py SMPL_NEUTRAL.pkl smpl_neutral.h5
    /usr/bin/python3 data_tools/smpl_pkl_to_h5.py SMPL_NEUTRAL.npz smpl_neutral.h5

Needs only numpy, scipy and h5py (Debian: python3-numpy python3-scipy python3-h5py).
The official .pkl is a Python 2 pickle holding chumpy `Ch` objects (shapedirs,
sometimes v_template/posedirs/J) and a scipy.sparse csc_matrix (J_regressor).
chumpy is not needed: a restricted unpickler maps every chumpy class to a stub
that keeps its pickled state (the array is state['x']), rebuilds scipy.sparse
matrices from their pickled (data, indices, indptr, shape) itself, and maps
any class it does not know to an inert stub, so loading never runs foreign code.

The HDF5 layout is documented in include/sflsh/body/body_model_io.hpp and
data_tools/README.md.

    --make-test-pkl MODEL.npz OUT.pkl   wraps an .npz model into an SMPL-like
        pickle (chumpy-style Ch objects, a csc J_regressor, protocol 2) without
        chumpy, for tests of this converter.
    --self-test   converts such a pickle built from the tiny test model (smpl_reference.py) and
        compares every array with h5py.
"""
import argparse
import io
import os
import pickle
import sys
import tempfile
import types
import zipfile

import numpy as np

FORMAT_VERSION = 1
NUM_JOINTS = 24
NUM_POSE_FEATURES = 207
SMPL_JOINT_NAMES = [
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "left_ankle",
    "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar", "right_collar", "head",
    "left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hand",
    "right_hand"]
KEYS = ("v_template", "f", "shapedirs", "posedirs", "J_regressor", "weights", "kintree_table")


class ConversionError(Exception):
    pass


# --- unpickling without chumpy ---------------------------------------------------------------

class _Stub:
    """Stands in for a class we do not import: remembers constructor args and state."""
    _module = "?"
    _name = "?"

    def __init__(self, *args, **kwargs):
        self.__dict__["_args"] = args
        self.__dict__["_state"] = {}

    def __setstate__(self, state):
        # pickle may pass (dict_state, slot_state).
        if isinstance(state, tuple) and len(state) == 2 and all(s is None or isinstance(s, dict) for s in state):
            merged = {}
            for s in state:
                merged.update(s or {})
            state = merged
        self.__dict__["_state"] = state if isinstance(state, dict) else {"x": state}

    def __repr__(self):
        return f"<stub {self._module}.{self._name}>"


def _stub_class(module, name):
    return type(name, (_Stub,), {"_module": module, "_name": name})


# numpy and a few builtins are needed to rebuild arrays; nothing else is imported.
_SAFE_BUILTINS = {"object", "set", "frozenset", "list", "dict", "tuple", "int", "float", "complex", "bytes",
                  "str", "bytearray", "slice", "range", "bool"}


class SmplUnpickler(pickle.Unpickler):
    def find_class(self, module, name):
        if module in ("__builtin__", "builtins") and name in _SAFE_BUILTINS:
            return super().find_class("builtins", name)
        if module in ("copy_reg", "copyreg") and name == "_reconstructor":
            return super().find_class("copyreg", name)
        if module == "_codecs" and name == "encode":  # how protocol-2 pickles from Python 3 spell bytes
            return super().find_class(module, name)
        if module == "numpy" or module.startswith("numpy."):
            return super().find_class(module, name)
        return _stub_class(module, name)  # chumpy.ch.Ch, scipy.sparse.csc.csc_matrix, anything else


def load_pickle(path):
    with open(path, "rb") as fh:
        try:
            return SmplUnpickler(fh, encoding="latin1").load()
        except Exception as e:  # truncated or not a pickle
            raise ConversionError(f"{path}: cannot unpickle ({type(e).__name__}: {e})") from None


def to_array(value, key, path):
    """ndarray for an ndarray / chumpy stub / sparse stub / scipy sparse value."""
    import scipy.sparse as sp
    if isinstance(value, _Stub):
        st = value._state
        if "indptr" in st and "indices" in st and "data" in st:  # scipy csc/csr
            shape = tuple(st.get("_shape", st.get("shape")))
            args = (np.asarray(st["data"]), np.asarray(st["indices"]), np.asarray(st["indptr"]))
            cls = sp.csr_matrix if "csr" in value._name else sp.csc_matrix
            return cls(args, shape=shape)
        if "row" in st and "col" in st and "data" in st:  # scipy coo
            shape = tuple(st.get("_shape", st.get("shape")))
            return sp.coo_matrix((np.asarray(st["data"]), (np.asarray(st["row"]), np.asarray(st["col"]))), shape=shape)
        if "x" in st:  # chumpy Ch: the value itself
            return np.asarray(st["x"])
        raise ConversionError(f"{path}: key '{key}' is a {value._module}.{value._name} object without a stored "
                              f"array (a derived chumpy expression?); state keys: {sorted(st)}")
    if sp.issparse(value):
        return value
    return np.asarray(value)


def load_npz(path):
    """Entries of an .npz; object entries (pickled sparse matrices) go through SmplUnpickler."""
    out = {}
    try:
        zf = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError) as e:
        raise ConversionError(f"{path}: not a readable .npz archive ({e})") from None
    with zf:
        for name in zf.namelist():
            key = name[:-4] if name.endswith(".npy") else name
            buf = io.BytesIO(zf.read(name))
            version = np.lib.format.read_magic(buf)
            shape, fortran, dtype = np.lib.format._read_array_header(buf, version)
            if dtype.hasobject:
                out[key] = SmplUnpickler(buf, encoding="latin1").load()
            else:
                buf.seek(0)
                out[key] = np.lib.format.read_array(buf, allow_pickle=False)
    return out


# --- checking and writing --------------------------------------------------------------------

def extract(raw, path):
    """The SMPL arrays as checked numpy arrays (float64, int32) and a CSR regressor."""
    import scipy.sparse as sp
    m = {}
    for key in KEYS:
        if key not in raw:
            raise ConversionError(f"{path}: key '{key}' is missing (have: {', '.join(sorted(map(str, raw)))})")
        m[key] = to_array(raw[key], key, path)

    def need(key, shape):
        got = m[key].shape
        if len(got) != len(shape) or any(e >= 0 and e != g for e, g in zip(shape, got)):
            want = "(" + ", ".join("any" if e < 0 else str(e) for e in shape) + ")"
            raise ConversionError(f"{path}: key '{key}' has shape {tuple(got)}, expected {want}")

    need("v_template", (-1, 3))
    V = m["v_template"].shape[0]
    need("f", (-1, 3))
    need("shapedirs", (V, 3, -1))
    need("posedirs", (V, 3, NUM_POSE_FEATURES))
    need("J_regressor", (NUM_JOINTS, V))
    need("weights", (V, NUM_JOINTS))
    need("kintree_table", (2, NUM_JOINTS))

    out = {}
    for key in ("v_template", "shapedirs", "posedirs", "weights"):
        a = np.asarray(m[key], dtype=np.float64)
        if not np.all(np.isfinite(a)):
            raise ConversionError(f"{path}: key '{key}' holds non-finite values")
        out[key] = np.ascontiguousarray(a)
    f = np.asarray(m["f"])
    if not np.issubdtype(f.dtype, np.integer) and not np.all(f == np.floor(f)):
        raise ConversionError(f"{path}: key 'f' holds non-integer values")
    f = f.astype(np.int64)
    if f.size and (f.min() < 0 or f.max() >= V):
        raise ConversionError(f"{path}: key 'f' holds vertex indices outside [0, {V})")
    out["f"] = f.astype(np.int32)
    kt = np.asarray(m["kintree_table"]).astype(np.int64)
    parents = kt[0].copy()
    parents[0] = -1  # SMPL stores 4294967295 for the root
    if not np.array_equal(kt[1], np.arange(NUM_JOINTS)) or np.any(parents[1:] < 0) or \
            np.any(parents[1:] >= np.arange(1, NUM_JOINTS)):
        raise ConversionError(f"{path}: key 'kintree_table' is not a tree in SMPL order (parents[j] < j)")
    out["kintree_table"] = np.stack([parents, np.arange(NUM_JOINTS)]).astype(np.int32)
    jr = m["J_regressor"]
    jr = sp.csr_matrix(jr if sp.issparse(jr) else np.asarray(jr, dtype=np.float64))
    jr.eliminate_zeros()
    jr.sort_indices()
    if not np.all(np.isfinite(jr.data)):
        raise ConversionError(f"{path}: key 'J_regressor' holds non-finite values")
    out["J_regressor"] = jr
    return out


def write_h5(m, out_path, source, shape_meanings=None):
    """Writes the model atomically (OUT.partial, renamed); shape_meanings: one string per shape
    direction (optional, /shape_meanings)."""
    import h5py
    tmp = out_path + ".partial"
    def strings(h, name, values):
        # Fixed-length byte strings holding UTF-8 (sflsh refuses variable-length
        # strings: libhdf5 reads them from its global heap without bounds checks).
        data = [v.encode("utf-8") for v in values]
        width = max(1, max(len(d) for d in data))
        h.create_dataset(name, data=np.array(data, dtype="S%d" % width))

    try:
        with h5py.File(tmp, "w") as h:
            h.create_dataset("meta/format_version", data=np.array([FORMAT_VERSION], dtype=np.int64))
            strings(h, "meta/units", ["metres"])
            strings(h, "meta/source", [source])
            for key in ("v_template", "f", "shapedirs", "posedirs", "weights", "kintree_table"):
                h.create_dataset(key, data=m[key], compression="gzip" if m[key].size >= 4096 else None)
            jr = m["J_regressor"]
            h.create_dataset("J_regressor_csr/indptr", data=jr.indptr.astype(np.int32))
            h.create_dataset("J_regressor_csr/indices", data=jr.indices.astype(np.int32))
            h.create_dataset("J_regressor_csr/data", data=jr.data.astype(np.float64))
            h.create_dataset("J_regressor_csr/shape", data=np.array(jr.shape, dtype=np.int32))
            strings(h, "joint_names", SMPL_JOINT_NAMES)
            if shape_meanings:
                strings(h, "shape_meanings", shape_meanings)
        os.replace(tmp, out_path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def convert(in_path, out_path):
    ext = os.path.splitext(in_path)[1].lower()
    if not os.path.exists(in_path):
        raise ConversionError(f"{in_path}: file not found")
    raw = load_npz(in_path) if ext == ".npz" else load_pickle(in_path)
    if not isinstance(raw, dict):
        raise ConversionError(f"{in_path}: expected a dict of SMPL arrays, found {type(raw).__name__}")
    m = extract(raw, in_path)
    write_h5(m, out_path, os.path.basename(in_path))
    print(f"{out_path}: {m['v_template'].shape[0]} vertices, {m['f'].shape[0]} faces, "
          f"{m['shapedirs'].shape[2]} shape directions, J_regressor {m['J_regressor'].nnz} non-zeros")


# --- test support ----------------------------------------------------------------------------

def make_test_pkl(npz_path, out_path):
    """An SMPL-like pickle (chumpy-style objects, csc regressor) built from an .npz model."""
    import scipy.sparse as sp
    with np.load(npz_path, allow_pickle=False) as z:
        src = {k: np.array(z[k]) for k in KEYS}
    # Classes that pickle under chumpy's and old scipy's names; registered only while dumping.
    Ch = type("Ch", (), {"__module__": "chumpy.ch"})
    Csc = type("csc_matrix", (), {"__module__": "scipy.sparse.csc"})
    fake = {"chumpy": types.ModuleType("chumpy"), "chumpy.ch": types.ModuleType("chumpy.ch"),
            "scipy.sparse.csc": types.ModuleType("scipy.sparse.csc")}
    fake["chumpy.ch"].Ch = Ch
    fake["scipy.sparse.csc"].csc_matrix = Csc

    def ch(a):
        o = Ch()
        o.__dict__.update({"x": a, "_cache": {}, "_parents": {}})
        return o

    jr = sp.csc_matrix(src["J_regressor"].astype(np.float64))
    sparse = Csc()
    sparse.__dict__.update({"data": jr.data, "indices": jr.indices, "indptr": jr.indptr, "_shape": jr.shape,
                            "maxprint": 50})
    d = {"v_template": ch(src["v_template"]), "f": src["f"], "shapedirs": ch(src["shapedirs"]),
         "posedirs": src["posedirs"], "J_regressor": sparse, "weights": src["weights"],
         "kintree_table": src["kintree_table"], "bs_style": "lbs", "bs_type": "lrotmin",
         "J": ch(src["J_regressor"].astype(np.float64) @ src["v_template"])}
    saved = {k: sys.modules.get(k) for k in fake}
    sys.modules.update(fake)
    try:
        with open(out_path, "wb") as fh:
            pickle.dump(d, fh, protocol=2)
    finally:
        for k, v in saved.items():
            if v is None:
                sys.modules.pop(k, None)
            else:
                sys.modules[k] = v


def self_test():
    import h5py
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, here)
    import smpl_reference  # the tiny test model's generator
    with tempfile.TemporaryDirectory() as tmp:
        smpl_reference.make_fixtures(tmp)
        npz = os.path.join(tmp, "tiny_smpl.npz")
        pkl, h5 = os.path.join(tmp, "tiny.pkl"), os.path.join(tmp, "tiny.h5")
        make_test_pkl(npz, pkl)
        raw = open(pkl, "rb").read()
        assert b"chumpy.ch" in raw and b"scipy.sparse.csc" in raw, "the test pickle must reference chumpy and scipy"
        assert "chumpy" not in sys.modules, "chumpy must not be importable for this test"
        convert(pkl, h5)
        with np.load(npz) as z, h5py.File(h5, "r") as h:
            for key in ("v_template", "shapedirs", "posedirs", "weights", "f"):
                assert np.array_equal(h[key][()], z[key]), key
            g = h["J_regressor_csr"]
            import scipy.sparse as sp
            jr = sp.csr_matrix((g["data"][()], g["indices"][()], g["indptr"][()]), shape=tuple(g["shape"][()]))
            assert np.array_equal(jr.toarray(), z["J_regressor"].astype(np.float64)), "J_regressor"
            assert h["kintree_table"][0, 0] == -1 and np.array_equal(h["kintree_table"][0, 1:], z["kintree_table"][0, 1:])
        # Broken inputs must fail with a message naming the problem.
        open(os.path.join(tmp, "cut.pkl"), "wb").write(raw[: len(raw) // 2])
        for bad, expect in ((os.path.join(tmp, "cut.pkl"), "cannot unpickle"),):
            try:
                convert(bad, os.path.join(tmp, "bad.h5"))
                raise AssertionError(f"{bad} converted")
            except ConversionError as e:
                assert expect in str(e), str(e)
        # .npz input converts to the same file contents.
        h5b = os.path.join(tmp, "tiny_npz.h5")
        convert(npz, h5b)
        with h5py.File(h5, "r") as a, h5py.File(h5b, "r") as b:
            for key in ("v_template", "shapedirs", "posedirs", "weights", "f", "J_regressor_csr/data"):
                assert np.array_equal(a[key][()], b[key][()]), key
    print("self-test passed")


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("input", nargs="?", help="SMPL model .pkl or .npz")
    ap.add_argument("output", nargs="?", help="output .h5")
    ap.add_argument("--make-test-pkl", nargs=2, metavar=("MODEL_NPZ", "OUT_PKL"))
    ap.add_argument("--self-test", action="store_true")
    args = ap.parse_args(argv)
    try:
        if args.self_test:
            self_test()
        elif args.make_test_pkl:
            make_test_pkl(*args.make_test_pkl)
        elif args.input and args.output:
            convert(args.input, args.output)
        else:
            ap.error("give INPUT and OUTPUT (or --self-test / --make-test-pkl)")
    except ConversionError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
