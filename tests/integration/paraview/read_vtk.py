#!/usr/bin/env python3
"""Reads every ParaView file of a crumble run folder with VTK's own readers (python3-vtk9).

    read_vtk.py DIR [--cell-fields a,b,...] [--contacts] [--analyses] [--point-fields a,b]

Checks, for every file listed in DIR/grains.pvd, DIR/scene.pvd and (with --analyses)
DIR/analyses.pvd: the reader opens it without error, the counts are consistent (cells > 0
in at least one grains snapshot, every cell field has one tuple per cell, every point field one per point), the
requested fields are there, and no value is NaN or infinite. Prints one JSON object with
what it read (the C++ test compares it with summary.json). Exit 3 when vtk is missing,
1 on the first failure (the message says which file and what).
"""
import json
import math
import os
import sys
import xml.etree.ElementTree as ET

try:
    import vtk  # noqa: F401
    from vtkmodules.vtkIOXML import vtkXMLMultiBlockDataReader, vtkXMLPolyDataReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
except ImportError as e:  # pragma: no cover
    print(f"python3-vtk9 missing: {e}")
    sys.exit(3)


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def pvd_entries(path):
    if not os.path.exists(path):
        fail(f"{path} missing")
    root = ET.parse(path).getroot()
    out = []
    for ds in root.iter("DataSet"):
        out.append((float(ds.get("timestep")), ds.get("part"), ds.get("file")))
    return out


def arrays(data):
    res = {}
    for i in range(data.GetNumberOfArrays()):
        a = data.GetArray(i)
        res[a.GetName()] = a
    return res


def check_finite(arr, where):
    v = vtk_to_numpy(arr)
    if v.size and not all(math.isfinite(float(x)) for x in v.ravel()):
        fail(f"{where}: array {arr.GetName()} holds a non-finite value")


def read_polydata(path):
    r = vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    if r.GetErrorCode() != 0:
        fail(f"{path}: VTK reader error {r.GetErrorCode()}")
    pd = r.GetOutput()
    if pd is None:
        fail(f"{path}: no output")
    return pd


def check_polydata(pd, path, cell_fields=(), point_fields=()):
    n_pts, n_cells = pd.GetNumberOfPoints(), pd.GetNumberOfCells()
    check_finite(pd.GetPoints().GetData(), path) if n_pts else None
    cells = arrays(pd.GetCellData())
    pts = arrays(pd.GetPointData())
    for name in cell_fields:
        if name not in cells:
            fail(f"{path}: no cell field '{name}' (has {sorted(cells)})")
    for name in point_fields:
        if name not in pts:
            fail(f"{path}: no point field '{name}' (has {sorted(pts)})")
    for name, a in cells.items():
        if a.GetNumberOfTuples() != n_cells:
            fail(f"{path}: cell field {name} has {a.GetNumberOfTuples()} tuples for {n_cells} cells")
        check_finite(a, path)
    for name, a in pts.items():
        if a.GetNumberOfTuples() != n_pts:
            fail(f"{path}: point field {name} has {a.GetNumberOfTuples()} tuples for {n_pts} points")
        check_finite(a, path)
    return {"points": n_pts, "cells": n_cells, "cell_fields": sorted(cells), "point_fields": sorted(pts)}


def main():
    args = sys.argv[1:]
    if not args:
        fail("usage: read_vtk.py DIR [--cell-fields a,b] [--contacts] [--analyses] [--point-fields a,b]")
    d = args[0]
    opts = {"--cell-fields": "", "--point-fields": ""}
    flags = set()
    i = 1
    while i < len(args):
        if args[i] in opts:
            opts[args[i]] = args[i + 1]
            i += 2
        else:
            flags.add(args[i])
            i += 1
    want_cells = [x for x in opts["--cell-fields"].split(",") if x]
    want_points = [x for x in opts["--point-fields"].split(",") if x]
    report = {"grains": [], "scene": [], "analyses": []}

    for t, _, f in pvd_entries(os.path.join(d, "grains.pvd")):
        path = os.path.join(d, f)
        pd = read_polydata(path)
        # A snapshot without grains (an open scene before its first rock) has no fields to check.
        info = check_polydata(pd, path, want_cells if pd.GetNumberOfCells() else ["grain"])
        ids = vtk_to_numpy(pd.GetCellData().GetArray("grain"))
        info["grains"] = int(len(set(int(x) for x in ids)))
        info["max_crush_count"] = int(max(vtk_to_numpy(pd.GetCellData().GetArray("crush_count")), default=0))
        info["time"] = t
        report["grains"].append(info)

    if not any(g["cells"] for g in report["grains"]):
        fail(f"{d}/grains.pvd: no snapshot has a grain")

    for t, _, f in pvd_entries(os.path.join(d, "scene.pvd")):
        path = os.path.join(d, f)
        r = vtkXMLMultiBlockDataReader()
        r.SetFileName(path)
        r.Update()
        mb = r.GetOutput()
        names = {}
        for b in range(mb.GetNumberOfBlocks()):
            name = mb.GetMetaData(b).Get(mb.NAME())
            blk = mb.GetBlock(b)
            if blk is None:
                fail(f"{path}: block {name} could not be read")
            grain_fields = want_cells if blk.GetNumberOfCells() else ["grain"]
            fields = {"grains": grain_fields, "walls": ["wall"], "platen": ["force_N", "stress_Pa"],
                      "contacts": ["grain_a", "grain_b", "wall", "normal_force_N", "force_N", "normal"]}.get(name, [])
            names[name] = check_polydata(blk, f"{path}:{name}", fields)
        if "grains" not in names or "walls" not in names:
            fail(f"{path}: blocks {sorted(names)}, expected grains and walls")
        if "--contacts" in flags and "contacts" not in names:
            fail(f"{path}: no contacts block")
        report["scene"].append({"time": t, "blocks": names})

    if "--analyses" in flags:
        for t, part, f in pvd_entries(os.path.join(d, "analyses.pvd")):
            path = os.path.join(d, f)
            pd = read_polydata(path)
            info = check_polydata(pd, path, (), want_points)
            if info["points"] == 0 or info["cells"] != info["points"]:
                fail(f"{path}: {info['points']} points, {info['cells']} vertex cells")
            dmg = vtk_to_numpy(pd.GetPointData().GetArray("damage")) if "damage" in info["point_fields"] else []
            info["max_damage"] = float(max(dmg, default=0.0))
            info["time"] = t
            info["part"] = part
            report["analyses"].append(info)
    print(json.dumps(report))


if __name__ == "__main__":
    main()
