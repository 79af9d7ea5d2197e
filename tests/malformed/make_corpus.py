#!/usr/bin/env python3
"""Writes the malformed-input corpus under tests/malformed/ (every subdirectory; the
twelve mesh files at the top level are hand-made and left alone).

Run from anywhere:  python3 tests/malformed/make_corpus.py

Needs only the Python standard library (no NumPy): .npy and .npz files are written byte
by byte, so that each defect is exactly the one intended and the output is the same on
every run (zip members carry a fixed 1980-01-01 timestamp). Every file is described in
tests/malformed/README.md; crates/weft-cli/tests/malformed_cli.rs runs weft on them.
"""

import io
import json
import os
import shutil
import struct
import zipfile

ROOT = os.path.dirname(os.path.abspath(__file__))
SUBDIRS = ["body", "amass", "bvh", "map", "npy", "frames", "config", "dataset", "run"]


# ---------------------------------------------------------------------------- writers


def npy_bytes(descr, shape, data=b"", fortran=False, header=None, version=(1, 0)):
    """A .npy file: `data` is the raw element bytes; `header` replaces the dict text."""
    if header is None:
        header = f"{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': {tuple(shape)!r}, }}"
    head = header.encode("latin1")
    # Pad with spaces so that magic + version + length + header ends on 64 bytes, '\n' last.
    total = 10 + len(head) + 1
    head += b" " * ((64 - total % 64) % 64) + b"\n"
    return b"\x93NUMPY" + bytes(version) + struct.pack("<H", len(head)) + head + data


def pack(fmt, values):
    return struct.pack("<" + fmt * len(values), *values)


def f8(shape, values):
    return npy_bytes("<f8", shape, pack("d", values))


def f4(shape, values):
    return npy_bytes("<f4", shape, pack("f", values))


def i8(shape, values):
    return npy_bytes("<i8", shape, pack("q", values))


def i4(shape, values):
    return npy_bytes("<i4", shape, pack("i", values))


def corrupt(npz):
    """`npz` (written stored, not deflated) with one byte of its first member's data
    flipped: the archive opens, the member fails its CRC-32 check."""
    data = bytearray(npz)
    at = data.index(b"\x93NUMPY") + 200
    data[at] ^= 0xFF
    return bytes(data)


def npz_bytes(members, compress=True):
    """A .npz: `members` maps array names to .npy bytes (in order)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for name, data in members.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED
            info.external_attr = 0o644 << 16
            z.writestr(info, data)
    return buf.getvalue()


def write(rel, data):
    path = os.path.join(ROOT, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    if isinstance(data, str):
        data = data.encode("utf-8")
    with open(path, "wb") as f:
        f.write(data)


# ------------------------------------------------------------------- body (.npz, SMPL)

SMPL_PARENTS = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
V, J, B = 4, 24, 2
TETRA = [0.0, 0.0, 0.0, 0.3, 0.0, 0.0, 0.0, 0.3, 0.0, 0.0, 0.0, 0.3]
TETRA_FACES = [0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3]


def body(compress=True, **change):
    """A valid SMPL-format body of 4 vertices, 24 joints and 2 shape components (every
    vertex skinned to the pelvis, every joint the mean of the vertices), with `change`
    replacing members (None removes one)."""
    m = {
        "v_template": f8([V, 3], TETRA),
        "shapedirs": f8([V, 3, B], [0.01] * (V * 3 * B)),
        "J_regressor": f8([J, V], [1.0 / V] * (J * V)),
        "weights": f8([V, J], ([1.0] + [0.0] * (J - 1)) * V),
        "kintree_table": i8([2, J], SMPL_PARENTS + list(range(J))),
        "f": i4([4, 3], TETRA_FACES),
    }
    for k, v in change.items():
        if v is None:
            m.pop(k)
        else:
            m[k] = v
    return npz_bytes(m, compress)


def bodies():
    nan_v = list(TETRA)
    nan_v[4] = float("nan")
    inf_sd = [0.01] * (V * 3 * B)
    inf_sd[5] = float("inf")
    bad_parent = SMPL_PARENTS.copy()
    bad_parent[5] = 30
    child_first = SMPL_PARENTS.copy()
    child_first[4] = 7
    wrong_ids = list(range(J))
    wrong_ids[3], wrong_ids[4] = 4, 3
    heavy = ([0.7] + [0.0] * (J - 1)) * V
    negative = ([1.5, -0.5] + [0.0] * (J - 2)) * V
    regressor = [0.5 / V] * (J * V)
    two_j = npz_bytes(
        {
            "v_template": f8([V, 3], TETRA),
            "shapedirs": f8([V, 3, B], [0.01] * (V * 3 * B)),
            "J_regressor": f8([2, V], [1.0 / V] * (2 * V)),
            "weights": f8([V, 2], [1.0, 0.0] * V),
            "kintree_table": i8([2, 2], [-1, 0, 0, 1]),
            "f": i4([4, 3], TETRA_FACES),
        }
    )
    # A pickled object array, as SMPL's .pkl → .npz conversions leave J_regressor when it
    # was a scipy sparse matrix; the bytes after the header are never unpickled.
    pickled = npy_bytes("|O", [J, V], b"\x80\x02]q\x00.")
    good = body()
    files = {
        "missing_shapedirs.npz": body(shapedirs=None),
        "missing_faces.npz": body(f=None),
        "missing_kintree_table.npz": body(kintree_table=None),
        "v_template_int.npz": body(v_template=i4([V, 3], [0] * (V * 3))),
        "faces_float.npz": body(f=f8([4, 3], [float(i) for i in TETRA_FACES])),
        "v_template_two_columns.npz": body(v_template=f8([V, 2], [0.0] * (V * 2))),
        "shapedirs_2d.npz": body(shapedirs=f8([V, 3 * B], [0.01] * (V * 3 * B))),
        "weights_wrong_joints.npz": body(weights=f8([V, J - 1], ([1.0] + [0.0] * (J - 2)) * V)),
        "v_template_nan.npz": body(v_template=f8([V, 3], nan_v)),
        "shapedirs_inf.npz": body(shapedirs=f8([V, 3, B], inf_sd)),
        "kintree_parent_out_of_range.npz": body(kintree_table=i8([2, J], bad_parent + list(range(J)))),
        "kintree_child_before_parent.npz": body(kintree_table=i8([2, J], child_first + list(range(J)))),
        "kintree_ids_out_of_order.npz": body(kintree_table=i8([2, J], SMPL_PARENTS + wrong_ids)),
        "faces_index_out_of_range.npz": body(f=i4([4, 3], TETRA_FACES[:-1] + [4])),
        "faces_index_negative.npz": body(f=i4([4, 3], [-1] + TETRA_FACES[1:])),
        "no_faces.npz": body(f=i4([0, 3], [])),
        "weights_do_not_sum_to_one.npz": body(weights=f8([V, J], heavy)),
        "weights_negative.npz": body(weights=f8([V, J], negative)),
        "j_regressor_rows_sum_to_half.npz": body(J_regressor=f8([J, V], regressor)),
        "j_regressor_pickled.npz": body(J_regressor=pickled),
        "posedirs_wrong_shape.npz": body(posedirs=f8([V, 3, 5], [0.0] * (V * 15))),
        "zip_garbage.npz": b"PK\x03\x04" + bytes(range(7, 200)),
        "text.npz": "v_template = [[0, 0, 0]]\n",
        "truncated.npz": good[: len(good) // 2],
        "empty.npz": b"",
        "empty_archive.npz": npz_bytes({}),
        "corrupt_member.npz": corrupt(body(compress=False)),
        "member_header_lies.npz": body(v_template=npy_bytes("<f8", [400, 3], pack("d", TETRA))),
        "two_joints.npz": two_j,
    }
    for name, data in files.items():
        write(f"body/{name}", data)


# ----------------------------------------------------------------- AMASS motion (.npz)

T = 3


def amass(compress=True, **change):
    """A valid AMASS-style motion: 3 frames of SMPL poses at rest, 30 fps, 10 betas."""
    m = {
        "poses": f8([T, 72], [0.0] * (T * 72)),
        "trans": f8([T, 3], [0.0, 0.0, 0.9] * T),
        "mocap_framerate": f8([], [30.0]),
        "betas": f8([10], [0.0] * 10),
    }
    for k, v in change.items():
        if v is None:
            m.pop(k)
        else:
            m[k] = v
    return npz_bytes(m, compress)


def motions():
    nan_poses = [0.0] * (T * 72)
    nan_poses[72 + 7] = float("nan")
    inf_trans = [0.0, 0.0, 0.9] * T
    inf_trans[4] = float("inf")
    good = amass()
    files = {
        "no_poses.npz": amass(poses=None),
        "no_trans.npz": amass(trans=None),
        "no_framerate.npz": amass(mocap_framerate=None),
        "poses_1d.npz": amass(poses=f8([T * 72], [0.0] * (T * 72))),
        "poses_wrong_width.npz": amass(poses=f8([T, 50], [0.0] * (T * 50))),
        "poses_3d.npz": amass(poses=f8([T, 24, 3], [0.0] * (T * 72))),
        "poses_no_frames.npz": amass(poses=f8([0, 72], []), trans=f8([0, 3], [])),
        "poses_nan.npz": amass(poses=f8([T, 72], nan_poses)),
        "poses_int.npz": amass(poses=i8([T, 72], [0] * (T * 72))),
        "trans_short.npz": amass(trans=f8([T - 1, 3], [0.0] * ((T - 1) * 3))),
        "trans_inf.npz": amass(trans=f8([T, 3], inf_trans)),
        "trans_2_columns.npz": amass(trans=f8([T, 2], [0.0] * (T * 2))),
        "framerate_zero.npz": amass(mocap_framerate=f8([], [0.0])),
        "framerate_1e9.npz": amass(mocap_framerate=f8([], [1e9])),
        "framerate_negative.npz": amass(mocap_framerate=f8([], [-30.0])),
        "framerate_nan.npz": amass(mocap_framerate=f8([], [float("nan")])),
        "framerate_array.npz": amass(mocap_framerate=f8([2], [30.0, 60.0])),
        "frame_rate_zero.npz": amass(mocap_framerate=None, mocap_frame_rate=f8([], [0.0])),
        "betas_nan.npz": amass(betas=f8([3], [0.0, float("nan"), 0.0])),
        "betas_2d.npz": amass(betas=f8([T, 10], [0.0] * (T * 10))),
        "zip_garbage.npz": b"PK\x03\x04" + bytes(range(200, 10, -1)),
        "truncated.npz": good[: len(good) // 2],
        "empty.npz": b"",
        "corrupt_member.npz": corrupt(amass(compress=False)),
        "poses_header_lies.npz": amass(poses=npy_bytes("<f8", [T, 72], pack("d", [0.0] * 10))),
    }
    for name, data in files.items():
        write(f"amass/{name}", data)


# ------------------------------------------------------------------------------- BVH

# The nine joints SMPL retargeting needs (pelvis, hips, knees, shoulders, elbows), named
# as SMPL's own files name them, metres, Y up: a valid file before any change.
BVH_JOINTS = [
    # (name, parent, offset)
    ("Pelvis", None, (0.0, 0.0, 0.0)),
    ("L_Hip", "Pelvis", (0.1, -0.08, 0.0)),
    ("L_Knee", "L_Hip", (0.0, -0.4, 0.0)),
    ("R_Hip", "Pelvis", (-0.1, -0.08, 0.0)),
    ("R_Knee", "R_Hip", (0.0, -0.4, 0.0)),
    ("Spine3", "Pelvis", (0.0, 0.4, 0.0)),
    ("L_Shoulder", "Spine3", (0.17, 0.05, 0.0)),
    ("L_Elbow", "L_Shoulder", (0.28, 0.0, 0.0)),
    ("R_Shoulder", "Spine3", (-0.17, 0.05, 0.0)),
    ("R_Elbow", "R_Shoulder", (-0.28, 0.0, 0.0)),
]
END = {"L_Knee": (0.0, -0.4, 0.0), "R_Knee": (0.0, -0.4, 0.0), "L_Elbow": (0.25, 0.0, 0.0),
       "R_Elbow": (-0.25, 0.0, 0.0)}


def bvh_hierarchy():
    lines = ["HIERARCHY"]

    def emit(name, depth):
        parent = next(p for n, p, _ in BVH_JOINTS if n == name)
        offset = next(o for n, _, o in BVH_JOINTS if n == name)
        tab = "\t" * depth
        lines.append(f"{tab}{'ROOT' if parent is None else 'JOINT'} {name}")
        lines.append(f"{tab}{{")
        lines.append(f"{tab}\tOFFSET {offset[0]:g} {offset[1]:g} {offset[2]:g}")
        if parent is None:
            lines.append(f"{tab}\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation")
        else:
            lines.append(f"{tab}\tCHANNELS 3 Zrotation Yrotation Xrotation")
        children = [n for n, p, _ in BVH_JOINTS if p == name]
        for c in children:
            emit(c, depth + 1)
        if not children:
            e = END[name]
            lines.extend([f"{tab}\tEnd Site", f"{tab}\t{{", f"{tab}\t\tOFFSET {e[0]:g} {e[1]:g} {e[2]:g}", f"{tab}\t}}"])
        lines.append(f"{tab}}}")

    emit("Pelvis", 0)
    return "\n".join(lines) + "\n"


CHANNELS = 6 + 3 * (len(BVH_JOINTS) - 1)


def bvh(frames=None, declared=None, frame_time="0.0333333", hierarchy=None, motion_head=None):
    frames = frames if frames is not None else [["0", "0.9", "0"] + ["0"] * (CHANNELS - 3)] * 2
    head = motion_head if motion_head is not None else (
        f"MOTION\nFrames: {len(frames) if declared is None else declared}\nFrame Time: {frame_time}\n"
    )
    return (hierarchy if hierarchy is not None else bvh_hierarchy()) + head + "".join(
        " ".join(f) + "\n" for f in frames
    )


def bvhs():
    good = bvh()
    h = bvh_hierarchy()
    row = ["0", "0.9", "0"] + ["0"] * (CHANNELS - 3)
    files = {
        "empty.bvh": "",
        "binary_garbage.bvh": b"\x00\x01\x02garbage\xff\xfe\n",
        "truncated_hierarchy.bvh": good[: len(h) // 2],
        "missing_motion.bvh": h,
        "frame_count_mismatch.bvh": bvh(declared=3),
        "frame_count_negative.bvh": bvh(declared=-1),
        "frame_count_absurd.bvh": bvh(declared=4000000000000),
        "short_frame_line.bvh": bvh(frames=[row, row[:-2]]),
        "long_frame_line.bvh": bvh(frames=[row, row + ["0"]]),
        "non_numeric_channel.bvh": bvh(frames=[row, row[:5] + ["abc"] + row[6:]]),
        "nan_channel.bvh": bvh(frames=[row, row[:7] + ["nan"] + row[8:]]),
        "frame_time_zero.bvh": bvh(frame_time="0"),
        "frame_time_negative.bvh": bvh(frame_time="-0.033"),
        "frame_time_missing.bvh": bvh(motion_head="MOTION\nFrames: 2\n"),
        "unknown_channel.bvh": good.replace("Zrotation Yrotation Xrotation", "Zrotation Yrotation Wrotation", 1),
        "channel_count_mismatch.bvh": good.replace("CHANNELS 3 Zrotation", "CHANNELS 4 Zrotation", 1),
        "unbalanced_open_brace.bvh": good.replace("\t\t}\n\t}\n", "\t\t}\n", 1),
        "unbalanced_close_brace.bvh": good.replace("MOTION", "}\nMOTION", 1),
        "no_root.bvh": good.replace("ROOT Pelvis", "JOINT Pelvis", 1),
        "offset_not_numeric.bvh": good.replace("OFFSET 0.1 -0.08 0", "OFFSET 0.1 x 0", 1),
        "unmappable_joints.bvh": good.replace("L_Hip", "Tail1").replace("R_Hip", "Tail2"),
    }
    for name, data in files.items():
        write(f"bvh/{name}", data)


# -------------------------------------------------------------------- BVH name maps


def maps():
    files = {
        "syntax_error.toml": 'Hips = "pelvis\nLeftUpLeg = left_hip\n',
        "value_not_string.toml": "Hips = 3\n",
        "unknown_smpl_joint.toml": 'Hips = "pelvix"\n',
        "empty.toml": "",
        "conflicting.toml": 'Hips = "pelvis"\nHIPS = "spine1"\n',
        "binary_garbage.toml": b"\x00\xff\xfe garbage",
        "syntax_error.json": '{"Hips": "pelvis",',
        "not_an_object.json": '["Hips", "pelvis"]',
        "value_not_string.json": '{"Hips": ["pelvis"]}',
        "empty_object.json": "{}",
        "unknown_format.yaml": "Hips: pelvis\n",
        "no_joint_in_file.toml": 'Nothing = "pelvis"\nNobody = "left_hip"\n',
    }
    for name, data in files.items():
        write(f"map/{name}", data)


# ------------------------------------------------------------------- frames (.npy)

# Frames for a 3-vertex template (a triangle), 2 frames.
FRAME = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]


def npys():
    two = FRAME * 2
    nan = list(two)
    nan[10] = float("nan")
    inf = list(two)
    inf[3] = float("-inf")
    big = list(two)
    big[0] = 1e300
    files = {
        "int32.npy": i4([2, 3, 3], [int(x) for x in two]),
        "complex.npy": npy_bytes("<c8", [2, 3, 3], pack("f", two * 2)),
        "big_endian.npy": npy_bytes(">f4", [2, 3, 3], struct.pack(">18f", *two)),
        "object.npy": npy_bytes("|O", [2, 3, 3], b"\x80\x02]q\x00."),
        "two_d.npy": f4([2, 9], two),
        "one_d.npy": f4([18], two),
        "four_d.npy": f4([1, 2, 3, 3], two),
        "last_axis_2.npy": f4([3, 3, 2], two),
        "zero_frames.npy": f4([0, 3, 3], []),
        "wrong_vertex_count.npy": f4([1, 6, 3], two),
        "nan.npy": f4([2, 3, 3], nan),
        "inf.npy": f8([2, 3, 3], inf),
        "f64_beyond_f32.npy": f8([2, 3, 3], big),
        "truncated.npy": f4([2, 3, 3], two)[:-10],
        "header_lies.npy": npy_bytes("<f4", [5, 3, 3], pack("f", two)),
        "header_huge.npy": npy_bytes("<f4", [10**12, 3, 3], pack("f", two)),
        "header_cut.npy": f4([2, 3, 3], two)[:30],
        "fortran_order.npy": npy_bytes("<f4", [2, 3, 3], pack("f", two), fortran=True),
        "unknown_header_key.npy": npy_bytes(
            "", [], pack("f", two),
            header="{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3, 3), 'x': 1}"),
        "version_9.npy": npy_bytes("<f4", [2, 3, 3], pack("f", two), version=(9, 0)),
        "not_npy.npy": "0 0 0\n1 0 0\n0 1 0\n",
        "empty.npy": b"",
    }
    for name, data in files.items():
        write(f"npy/{name}", data)


# ------------------------------------------------------- frame directories (OBJ frames)

TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
QUAD = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n"


def frame_dirs():
    files = {
        "mixed_vertex_counts/frame_00000.obj": TRI,
        "mixed_vertex_counts/frame_00001.obj": QUAD,
        "bad_frame/frame_00000.obj": TRI,
        "bad_frame/frame_00001.obj": "v 0 0 0\nv 1 0\n",
        "no_obj_files/notes.txt": "frames were meant to be here\n",
        "nan_frame/frame_00000.obj": TRI,
        "nan_frame/frame_00001.obj": TRI.replace("v 1 0 0", "v nan 0 0"),
    }
    for name, data in files.items():
        write(f"frames/{name}", data)


# ------------------------------------------------------------------- configs (TOML)

DATA_BASE = """seed = 0
fps = 30.0
frames = 2
substeps = 2
warmup_frames = 0
material = "cotton"

[train]
betas = [[0.0]]
garments = [{ kind = "skirt", vertices = 500, seed = 1 }]
motions = [{ kind = "walk", seed = 1, frames = 2 }]

[validation]
betas = [[1.0]]
garments = [{ kind = "skirt", vertices = 500, seed = 2 }]
motions = [{ kind = "walk", seed = 2, frames = 2 }]

[test]
betas = [[-1.0]]
garments = [{ kind = "skirt", vertices = 500, seed = 3 }]
motions = [{ kind = "walk", seed = 3, frames = 2 }]
"""


def data_config(old, new, count=1):
    assert old in DATA_BASE, old
    return DATA_BASE.replace(old, new, count)


def configs():
    data = {
        "syntax_error.toml": data_config("frames = 2\n", "frames = = 2\n"),
        "unknown_top_key.toml": data_config("seed = 0\n", "seed = 0\nfpss = 30\n"),
        "unknown_nested_key.toml": data_config("[train]\n", "[train]\ngarmentz = []\n"),
        "unknown_garment_key.toml": data_config("vertices = 500, seed = 1", "vertices = 500, seed = 1, colour = \"red\""),
        "unknown_section.toml": DATA_BASE + "\n[trian]\nbetas = [[0.0]]\n",
        "frames_string.toml": data_config("frames = 2\n", "frames = \"many\"\n"),
        "seed_negative.toml": data_config("seed = 0\n", "seed = -1\n"),
        "fps_string.toml": data_config("fps = 30.0\n", "fps = \"30\"\n"),
        "betas_not_array.toml": data_config("betas = [[0.0]]", "betas = 0.0"),
        "fps_zero.toml": data_config("fps = 30.0\n", "fps = 0.0\n"),
        "fps_huge.toml": data_config("fps = 30.0\n", "fps = 1e9\n"),
        "fps_nan.toml": data_config("fps = 30.0\n", "fps = nan\n"),
        "frames_zero.toml": data_config("frames = 2\n", "frames = 0\n"),
        "substeps_zero.toml": data_config("substeps = 2\n", "substeps = 0\n"),
        "substeps_1000.toml": data_config("substeps = 2\n", "substeps = 1000\n"),
        "warmup_frames_huge.toml": data_config("warmup_frames = 0\n", "warmup_frames = 1000000\n"),
        "material_unknown.toml": data_config("material = \"cotton\"", "material = \"kevlar\""),
        "beta_sigma_negative.toml": data_config("seed = 0\n", "seed = 0\nbeta_sigma = -1.0\n"),
        "beta_limit_zero.toml": data_config("seed = 0\n", "seed = 0\nbeta_limit = 0.0\n"),
        "beta_components_100.toml": data_config("seed = 0\n", "seed = 0\nbeta_components = 100\n"),
        "betas_nan.toml": data_config("betas = [[0.0]]", "betas = [[nan]]"),
        "garment_kind_unknown.toml": data_config("kind = \"skirt\", vertices = 500, seed = 1", "kind = \"cape\", vertices = 500, seed = 1"),
        "garment_vertices_10.toml": data_config("vertices = 500, seed = 1", "vertices = 10, seed = 1"),
        "garment_material_unknown.toml": data_config("vertices = 500, seed = 1", "vertices = 500, seed = 1, material = \"kevlar\""),
        "motion_kind_unknown.toml": data_config("kind = \"walk\", seed = 1", "kind = \"moonwalk\", seed = 1"),
        "motion_kind_and_file.toml": data_config("kind = \"walk\", seed = 1", "kind = \"walk\", file = \"walk.npz\", seed = 1"),
        "motion_frames_zero.toml": data_config("seed = 1, frames = 2 }", "seed = 1, frames = 0 }"),
        "motion_file_missing.toml": data_config("{ kind = \"walk\", seed = 1, frames = 2 }", "{ file = \"no_such_motion.npz\" }"),
        "motion_file_malformed.toml": data_config("{ kind = \"walk\", seed = 1, frames = 2 }", "{ file = \"../../amass/poses_nan.npz\" }"),
        "no_garments.toml": data_config("garments = [{ kind = \"skirt\", vertices = 500, seed = 1 }]\n", ""),
        "body_missing.toml": data_config("seed = 0\n", "seed = 0\nbody = \"no_such_body.npz\"\n"),
        "body_malformed.toml": data_config("seed = 0\n", "seed = 0\nbody = \"../../body/kintree_parent_out_of_range.npz\"\n"),
        "empty.toml": "",
        "binary_garbage.toml": b"\x00\x01\xff garbage\n",
    }
    for name, text in data.items():
        write(f"config/data/{name}", text)

    train = {
        "syntax_error.toml": "[train]\nsteps = \n",
        "unknown_top_key.toml": "stepz = 10\n",
        "unknown_section.toml": "[trian]\nsteps = 10\n",
        "unknown_model_key.toml": "[model]\nfeature_widht = 32\n",
        "unknown_nested_key.toml": "[train.optimizer]\nmomentum = 0.9\n",
        "steps_string.toml": "[train]\nsteps = \"many\"\n",
        "steps_negative.toml": "[train]\nsteps = -5\n",
        "steps_zero.toml": "[train]\nsteps = 0\n",
        "window_zero.toml": "[train]\nwindow = 0\n",
        "batch_zero.toml": "[train]\nbatch = 0\n",
        "learning_rate_negative.toml": "[train]\nlearning_rate = -0.1\n",
        "learning_rate_nan.toml": "[train]\nlearning_rate = nan\n",
        "optimizer_unknown.toml": "[train.optimizer]\nkind = \"adamx\"\n",
        "pool_ratio_2.toml": "[model]\npool_ratio = 2.0\n",
        "pooling_unknown.toml": "[model]\npooling = \"random\"\n",
        "joints_wrong_type.toml": "[model]\njoints = \"24\"\n",
        "model_not_table.toml": "model = 3\n",
        "preset_unknown.toml": "preset = \"gpu\"\n",
        "binary_garbage.toml": b"\x00\x01\xff garbage\n",
    }
    for name, text in train.items():
        write(f"config/train/{name}", text)


# ---------------------------------------------------------------- dataset directories


def datasets():
    files = {
        "manifest_not_json/manifest.json": "this is not JSON\n",
        "manifest_empty/manifest.json": "",
        "manifest_array/manifest.json": "[]\n",
        "manifest_truncated/manifest.json": '{"format": "weft-dataset", "version": 1, "seed": 0, "body_model": ',
        "manifest_wrong_format/manifest.json": '{"format": "somebody-elses-dataset", "version": 1}\n',
        "no_manifest/shards/README": "a dataset directory whose manifest.json is missing\n",
        "bad_part/manifest.part-0-of-2.json": '{"format": "weft-dataset", "version": 1, "job": ',
    }
    for name, data in files.items():
        write(f"dataset/{name}", data)


# -------------------------------------------------------------------- run directories

# The header and an empty [model] table: the preset's defaults, as a run's config.toml.
RUN_CONFIG_HEAD = 'format_version = 1\nmodel_kind = "multilevel"\npreset = "cpu"\n\n[model]\n'


def runs():
    files = {
        "no_config/checkpoints/latest": "step-000100.bpk\n",
        "config_syntax_error/config.toml": "format_version = = 1\n",
        "config_no_version/config.toml": 'model_kind = "multilevel"\npreset = "cpu"\n',
        "config_version_99/config.toml": 'format_version = 99\nmodel_kind = "multilevel"\npreset = "cpu"\n',
        "config_unknown_model/config.toml": 'format_version = 1\nmodel_kind = "transformer"\npreset = "cpu"\n',
        "config_no_preset/config.toml": 'format_version = 1\nmodel_kind = "multilevel"\n',
        "config_hood_unknown_key/config.toml": RUN_CONFIG_HEAD.replace("multilevel", "hood")
        + "latnet = 32\n",
        "config_unknown_model_key/config.toml": RUN_CONFIG_HEAD + "feature_widht = 32\n",
        "config_no_model_table/config.toml": 'format_version = 1\nmodel_kind = "multilevel"\npreset = "cpu"\n',
        "config_binary/config.toml": b"\x00\x01\xff\n",
        "no_checkpoint/config.toml": RUN_CONFIG_HEAD,
        "latest_garbage/config.toml": RUN_CONFIG_HEAD,
        "latest_garbage/checkpoints/latest": "the newest one\n",
        "latest_dangling/config.toml": RUN_CONFIG_HEAD,
        "latest_dangling/checkpoints/latest": "step-000100.bpk\n",
        "checkpoint_garbage/config.toml": RUN_CONFIG_HEAD,
        "checkpoint_garbage/checkpoints/latest": "step-000100.bpk\n",
        "checkpoint_garbage/checkpoints/step-000100.bpk": b"\x00garbage, not a burnpack record\xff",
        "checkpoint_empty/config.toml": RUN_CONFIG_HEAD,
        "checkpoint_empty/checkpoints/latest": "step-000100.bpk\n",
        "checkpoint_empty/checkpoints/step-000100.bpk": b"",
    }
    for name, data in files.items():
        write(f"run/{name}", data)


def main():
    for d in SUBDIRS:
        shutil.rmtree(os.path.join(ROOT, d), ignore_errors=True)
    bodies()
    motions()
    bvhs()
    maps()
    npys()
    frame_dirs()
    configs()
    datasets()
    runs()
    count = sum(len(fs) for d in SUBDIRS for _, _, fs in os.walk(os.path.join(ROOT, d)))
    print(f"wrote {count} files under {ROOT}")


if __name__ == "__main__":
    main()
