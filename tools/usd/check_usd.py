#!/usr/bin/env python3
"""Checks USD files with Pixar's own library, as `usdchecker` does, and compares the
animated points of a mesh prim with weft's frames.

    python tools/usd/check_usd.py FILE.usda [--points PRIM=FRAMES.npy]... [--json]

Opens the stage (a parse error fails), runs every registered UsdValidation validator
on it (the framework behind `usdchecker` in USD 24.08 and later) and, for each
`--points`, reads the prim's `points` at every time code and compares them exactly
with the frames of a `(frames, vertices, 3)` little-endian float32 .npy written by weft.
Prints one summary line per file (or one JSON object with --json) and one line per
problem. Exit status: 0 clean, 1 validation errors or a mismatch, 2 bad usage.

Install: python3 -m venv tools/usd/.venv && tools/usd/.venv/bin/pip install -r tools/usd/requirements.txt
"""
import argparse
import ast
import json
import struct
import sys


def read_npy_f32(path):
    """A C-order little-endian float32 .npy as (shape, flat list); no numpy needed."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:6] != b"\x93NUMPY":
        raise ValueError(f"{path}: not a .npy file")
    major = data[6]
    if major == 1:
        (hlen,) = struct.unpack_from("<H", data, 8)
        start = 10
    else:
        (hlen,) = struct.unpack_from("<I", data, 8)
        start = 12
    header = ast.literal_eval(data[start:start + hlen].decode("latin1"))
    if header["descr"] != "<f4" or header["fortran_order"]:
        raise ValueError(f"{path}: expected little-endian float32 in C order")
    shape = tuple(header["shape"])
    count = 1
    for s in shape:
        count *= s
    values = struct.unpack_from(f"<{count}f", data, start + hlen)
    return shape, values


def check(path, points):
    from pxr import Usd, UsdGeom, UsdValidation

    problems = []
    stage = Usd.Stage.Open(path)
    context = UsdValidation.ValidationContext(
        UsdValidation.ValidationRegistry().GetOrLoadAllValidators())
    for error in context.Validate(stage):
        if error.GetType() == UsdValidation.ValidationErrorType.Error:
            problems.append(f"validation error {error.GetName()}: {error.GetMessage()}")
    summary = {
        "file": path,
        "up_axis": str(UsdGeom.GetStageUpAxis(stage)),
        "meters_per_unit": UsdGeom.GetStageMetersPerUnit(stage),
        "time_codes_per_second": stage.GetTimeCodesPerSecond(),
        "start": stage.GetStartTimeCode(),
        "end": stage.GetEndTimeCode(),
        "default_prim": str(stage.GetDefaultPrim().GetPath()),
        "meshes": {},
    }
    for prim in stage.Traverse():
        if prim.IsA(UsdGeom.Mesh):
            mesh = UsdGeom.Mesh(prim)
            st = UsdGeom.PrimvarsAPI(prim).GetPrimvar("st")
            summary["meshes"][str(prim.GetPath())] = {
                "points": len(mesh.GetPointsAttr().Get(Usd.TimeCode.EarliestTime()) or []),
                "time_samples": len(mesh.GetPointsAttr().GetTimeSamples()),
                "faces": len(mesh.GetFaceVertexCountsAttr().Get() or []),
                "st": st.GetInterpolation() if st and st.HasValue() else None,
                "st_indexed": bool(st and st.IsIndexed()),
            }
    for spec in points:
        prim_path, npy = spec.split("=", 1)
        shape, values = read_npy_f32(npy)
        prim = stage.GetPrimAtPath(prim_path)
        if not prim or not prim.IsA(UsdGeom.Mesh):
            problems.append(f"{prim_path}: no mesh prim")
            continue
        attr = UsdGeom.Mesh(prim).GetPointsAttr()
        frames, vertices = shape[0], shape[1]
        for k in range(frames):
            got = attr.Get(Usd.TimeCode(k))
            if got is None or len(got) != vertices:
                problems.append(f"{prim_path}: time code {k} has "
                                f"{0 if got is None else len(got)} points, expected {vertices}")
                break
            base = k * vertices * 3
            bad = next((i for i, p in enumerate(got)
                        if tuple(p) != tuple(values[base + 3 * i:base + 3 * i + 3])), None)
            if bad is not None:
                problems.append(f"{prim_path}: time code {k}, point {bad} is {tuple(got[bad])}, "
                                f"weft wrote {values[base + 3 * bad:base + 3 * bad + 3]}")
                break
    summary["problems"] = problems
    return summary


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="+")
    parser.add_argument("--points", action="append", default=[],
                        help="PRIM=FRAMES.npy: compare PRIM's points with these frames")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    status = 0
    for path in args.files:
        try:
            summary = check(path, args.points)
        except Exception as e:  # a stage that does not open is a failure, not a crash
            summary = {"file": path, "problems": [f"cannot open: {e}"]}
        if args.json:
            print(json.dumps(summary))
        else:
            print(f"{path}: {len(summary['problems'])} problems")
            for p in summary["problems"]:
                print(f"  {p}")
        if summary["problems"]:
            status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
