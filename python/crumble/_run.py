"""Reading a run folder (crumble run, crumble.run, or a run folder of compare / sweep): pure
Python, no compiled module needed. The files are described in README "Outputs" and
docs/output.md; every number is in SI units, named in the column (``platen_stress_Pa``)."""

import base64
import json
import os
import re
import xml.etree.ElementTree as ET
import zlib
from pathlib import Path

from ._errors import InputError

# The tables a Run reads, by attribute.
TABLES = {"series": "series.csv", "events": "events.csv", "psd": "psd.csv", "stages": "stages.csv"}
_SNAPSHOT = re.compile(r"^grains_(\d+)\.vtp$")
# Files of which one marks a folder as a run folder.
_MARKERS = ("summary.json", "effective_scenario.json", "checkpoint.json", "series.csv")


class Run:
    """One run folder. ``summary`` (dict of summary.json), ``series``, ``events``, ``psd``,
    ``stages`` (pandas DataFrames; the file's path in ``df.attrs["path"]``), ``steps`` (the
    steps with a grains snapshot in vtk/) and ``grains(step)`` (numpy arrays per grain)."""

    def __init__(self, path):
        self.path = Path(path)
        if not self.path.is_dir():
            raise InputError(f"{self.path}: not a folder (expected the --out folder of a run)")
        if not any((self.path / m).exists() for m in _MARKERS):
            raise InputError(f"{self.path}: not a crumble run folder (none of {', '.join(_MARKERS)})")

    def __repr__(self):
        return f"crumble.Run({str(self.path)!r})"

    def _json(self, name):
        f = self.path / name
        if not f.exists():
            return {}
        try:
            with f.open(encoding="utf-8") as fh:
                return json.load(fh)
        except ValueError as e:
            raise InputError(f"{f}: not valid JSON: {e}") from None

    @property
    def summary(self):
        """summary.json as a dict ({} while the run has not written it)."""
        return self._json("summary.json")

    @property
    def scenario(self):
        """effective_scenario.json: the scenario as run, every default filled in."""
        return self._json("effective_scenario.json")

    def table(self, name):
        """A CSV of the folder (e.g. "ncl.csv", "shape.csv") as a DataFrame."""
        return read_csv(self.path / name)

    series = property(lambda self: self.table(TABLES["series"]), doc="series.csv: the sampled state of the loading")
    events = property(lambda self: self.table(TABLES["events"]), doc="events.csv: one row per breakage analysis")
    psd = property(lambda self: self.table(TABLES["psd"]), doc="psd.csv: the particle-size distributions")
    stages = property(lambda self: self.table(TABLES["stages"]), doc="stages.csv: cost per stress stage")

    @property
    def steps(self):
        """The steps with a grains snapshot (vtk/grains_NNNNNNNN.vtp), ascending."""
        d = self.path / "vtk"
        if not d.is_dir():
            return []
        return sorted(int(m.group(1)) for m in map(_SNAPSHOT.match, os.listdir(d)) if m)

    def grains(self, step=None):
        """The grains of a snapshot (default: the last) as a dict of numpy arrays, one row per
        grain in the engine's order: ``id``, ``parent``, ``origin``, ``generation``,
        ``crush_count``, ``position`` (n×3, m), ``orientation`` (n×4 unit quaternion w x y z),
        ``diameter`` (equivalent, m), ``volume`` (m³; 2D m²), ``mass`` (kg; 2D per m),
        ``velocity``, ``angular_velocity``, the shape descriptors and the model's fields
        (docs/output.md, "grains")."""
        steps = self.steps
        if not steps:
            raise InputError(f"{self.path}/vtk: no grains snapshot (set output.vtk_every or output.vtk_final)")
        step = steps[-1] if step is None else step
        if step not in steps:
            raise InputError(f"{self.path}: no grains snapshot at step {step}; snapshots: {steps}")
        return read_grains_vtp(self.path / "vtk" / f"grains_{step:08d}.vtp")


def open_run(out_dir):
    """The run in ``out_dir`` (any run folder: crumble run, crumble.run, a compare or sweep
    setting's folder)."""
    return Run(out_dir)


def read_csv(f):
    """A CSV crumble wrote, as a DataFrame; its path in ``df.attrs["path"]``."""
    import pandas as pd

    if not f.exists():
        raise InputError(f"{f}: no such file")
    try:
        df = pd.read_csv(f)
    except (ValueError, pd.errors.ParserError) as e:
        raise InputError(f"{f}: cannot read as CSV: {e}") from None
    df.attrs["path"] = str(f)
    df.attrs["units"] = "SI; the unit ends each column name (_Pa, _m, _s, _N, _kg, _m3); others are counts or ratios"
    return df


def _vtk_values(a, root, path):
    """The numbers of one DataArray: ascii text, or crumble's binary arrays (VTK XML 1.0,
    header_type UInt64, zlib blocks: the header [blocks, block size, last block size,
    compressed sizes...] base64-encoded on its own, then the compressed blocks)."""
    import numpy as np

    dtype = np.int64 if a.get("type", "").startswith("Int") else np.float64
    fmt = a.get("format", "ascii")
    if fmt == "ascii":
        return np.array((a.text or "").split(), dtype=dtype)
    if fmt != "binary" or root.get("header_type") != "UInt64" or root.get("compressor") != "vtkZLibDataCompressor":
        raise InputError(f"{path}: DataArray '{a.get('Name')}' is {fmt} without UInt64 headers and zlib "
                         "(crumble reads its own ascii and binary files)")
    text = "".join((a.text or "").split())
    try:
        blocks = int(np.frombuffer(base64.b64decode(text[:12])[:8], dtype="<u8")[0])
        head_len = 4 * -(-8 * (3 + blocks) // 3)
        sizes = np.frombuffer(base64.b64decode(text[:head_len])[: 8 * (3 + blocks)], dtype="<u8")[3:]
        data = base64.b64decode(text[head_len:])
        out, at = [], 0
        for c in sizes:
            out.append(zlib.decompress(data[at : at + int(c)]))
            at += int(c)
    except (ValueError, zlib.error) as e:
        raise InputError(f"{path}: DataArray '{a.get('Name')}' cannot be decoded: {e}") from None
    return np.frombuffer(b"".join(out), dtype=np.dtype(dtype).newbyteorder("<")).astype(dtype)


def read_grains_vtp(path):
    """Per-grain arrays of a grains VTP file: its cell fields, one row per grain (a 3D grain
    has one cell per triangle, all with the grain's values)."""
    import numpy as np

    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise InputError(f"{path}: not a VTK XML file: {e}") from None
    cells = root.find("./PolyData/Piece/CellData")
    if cells is None:
        raise InputError(f"{path}: no CellData in the PolyData piece")
    fields = {}
    for a in cells.findall("DataArray"):
        v = _vtk_values(a, root, path)
        n = int(a.get("NumberOfComponents", "1"))
        fields[a.get("Name")] = v.reshape(-1, n) if n > 1 else v
    if "grain" not in fields:
        raise InputError(f"{path}: no 'grain' cell field (not a grains snapshot)")
    _, first = np.unique(fields["grain"], return_index=True)
    rows = np.sort(first)
    out = {("id" if k == "grain" else k): v[rows] for k, v in fields.items()}
    return out
