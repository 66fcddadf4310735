#!/usr/bin/env python3
"""PNG figures of a crumble output folder (matplotlib, Agg backend; Debian: python3-matplotlib).

    crumble_plot.py DIR [--quiet]

DIR is what `crumble run`, `crumble compare` or `crumble sweep` wrote. The figures are chosen
by what the folder holds (each is written under a temporary name and renamed when complete):

  run folder (summary.json, series.csv, ...):
    ncl.png               void ratio against log10 platen stress (normal compression line)
    psd.png               particle size distribution by mass at each psd.csv level
    breakage.png          grain count and breakage events against platen stress (crushable runs)
    fractal_dimension.png fractal dimension against stress, when a CSV carries one
    shape.png             2D: circularity and aspect-ratio histograms (first and last VTK
                          snapshot) and their means against strain; 3D: Zingg diagram
    load_displacement.png platen force against platen displacement (single-grain scenes)
    stress_strain.png     platen stress against axial strain (strain-controlled loading)
    product_psd.png       size distribution of the product (open scenes: jaw crusher)
  compare folder (comparison.csv): compare_ncl.png, compare_psd.png, compare_psd_levels.png
    (one panel per psd level a run reached), compare_shape.png, compare_breakage.png,
    compare_stress_strain.png (stress and void ratio), compare_load_displacement.png, compare_product_psd.png (open
    scenes): each run's curves overlaid
  sweep folder (sweep.csv): pareto.png, relative error against wall time, the front marked;
    and the compare figures of its runs

Exit status: 0 figures written; 2 the folder or one of its files cannot be read (the message
names the file and what is wrong); 3 matplotlib is not importable (nothing written); 1 any
other failure. One line per written file on stdout unless --quiet.
"""

import base64
import csv
import json
import math
import os
import struct
import sys
import xml.etree.ElementTree as ET
import zlib

EXIT_DATA = 2
EXIT_NO_MATPLOTLIB = 3


class DataError(Exception):
    """A file of the folder is missing, unreadable or garbled; the message names it."""


# ---------------------------------------------------------------------------------------------
# Reading the folder (nothing here needs matplotlib).

def read_table(path, required=(), numeric=None):
    """Rows of a CSV as dicts. `required` columns must exist; `numeric` columns (default: the
    required ones) must be finite numbers; any other column is a float where it reads as one."""
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except OSError as e:
        raise DataError(f"{path}: cannot read: {e.strerror}")
    except (csv.Error, UnicodeDecodeError) as e:
        raise DataError(f"{path}: not a CSV file: {e}")
    if not rows or not rows[0]:
        raise DataError(f"{path}: empty (expected a header line)")
    header = [h.strip() for h in rows[0]]
    for c in required:
        if c not in header:
            raise DataError(f"{path}: no column '{c}' in the header (columns: {', '.join(header)})")
    must = [c for c in (numeric if numeric is not None else required) if c in header]
    out = []
    for n, r in enumerate(rows[1:], start=2):
        if not r:
            continue
        if len(r) != len(header):
            raise DataError(f"{path}: line {n}: {len(r)} fields, the header has {len(header)}")
        d = dict(zip(header, r))
        for c in header:  # every other column: a number where it reads as one
            if c not in must:
                try:
                    d[c] = float(d[c])
                except ValueError:
                    pass
        for c in must:
            v = d.get(c, "")
            if v == "" and c not in required:
                d[c] = math.nan
                continue
            try:
                x = float(v)
            except ValueError:
                raise DataError(f"{path}: line {n}: column '{c}': '{v}' is not a number")
            if not math.isfinite(x):
                raise DataError(f"{path}: line {n}: column '{c}': {v} is not finite")
            d[c] = x
        out.append(d)
    return out, header


def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except OSError as e:
        raise DataError(f"{path}: cannot read: {e.strerror}")
    except ValueError as e:
        raise DataError(f"{path}: not valid JSON: {e}")


def optional_json(path):
    return read_json(path) if os.path.exists(path) else {}


def scenario_name(d, summary=None):
    s = summary if summary is not None else optional_json(os.path.join(d, "summary.json"))
    return s.get("scenario") or os.path.basename(os.path.normpath(d))


def vtk_snapshots(d):
    """(first, last) .vtp files of grains.pvd, or () when there is none."""
    pvd = os.path.join(d, "grains.pvd")
    if not os.path.exists(pvd):
        return ()
    try:
        files = [ds.get("file") for ds in ET.parse(pvd).getroot().iter("DataSet") if ds.get("file")]
    except ET.ParseError as e:
        raise DataError(f"{pvd}: not a VTK collection: {e}")
    files = [os.path.join(d, f) for f in files if os.path.exists(os.path.join(d, f))]
    return (files[0], files[-1]) if files else ()


def vtk_array_values(a, root):
    """The numbers of a DataArray element as floats: ascii, or crumble's binary arrays (VTK XML
    1.0 with UInt64 headers and zlib: the header [blocks, block size, last block size,
    compressed sizes...] base64-encoded on its own, then the compressed blocks); None for
    another encoding."""
    fmt = a.get("format", "ascii")
    if fmt == "ascii":
        return [float(x) for x in (a.text or "").split()]
    if fmt != "binary" or root.get("header_type") != "UInt64" or root.get("compressor") != "vtkZLibDataCompressor":
        return None
    text = "".join((a.text or "").split())
    blocks = struct.unpack("<Q", base64.b64decode(text[:12])[:8])[0]
    head_len = 4 * -(-8 * (3 + blocks) // 3)
    sizes = struct.unpack(f"<{3 + blocks}Q", base64.b64decode(text[:head_len])[: 8 * (3 + blocks)])[3:]
    data, raw, at = base64.b64decode(text[head_len:]), b"", 0
    for c in sizes:
        raw += zlib.decompress(data[at : at + c])
        at += c
    code = "q" if a.get("type", "").startswith("Int") else "d"
    return [float(x) for x in struct.unpack(f"<{len(raw) // 8}{code}", raw)]


def vtk_grain_values(path, names):
    """Per grain (first cell of each grain id) the CellData arrays `names` of a .vtp; {} when
    the file carries them in an encoding crumble does not write (the figure is then left out)."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise DataError(f"{path}: not a VTK XML file: {e}")
    arrays = {}
    for a in root.iter("DataArray"):
        if a.get("Name") in set(names) | {"grain"}:
            try:
                values = vtk_array_values(a, root)
            except (ValueError, struct.error, zlib.error) as e:
                raise DataError(f"{path}: DataArray '{a.get('Name')}' cannot be read: {e}")
            if values is None:
                return {}
            arrays[a.get("Name")] = values
    if "grain" not in arrays or any(n not in arrays for n in names):
        return {}
    seen, out = set(), {n: [] for n in names}
    for i, g in enumerate(arrays["grain"]):
        if g in seen:
            continue
        seen.add(g)
        for n in names:
            if i < len(arrays[n]) and arrays[n][i] >= 0:  # -1: no descriptor (a sliver)
                out[n].append(arrays[n][i])
    return out


# ---------------------------------------------------------------------------------------------
# Figures.

def setup_matplotlib():
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except Exception:  # ImportError, or a broken installation
        return None
    plt.rcParams.update({"figure.dpi": 110, "font.size": 10, "axes.grid": True, "grid.alpha": 0.3,
                         "axes.titlesize": 11, "legend.fontsize": 8, "legend.framealpha": 0.85})
    return plt


class Figures:
    def __init__(self, plt, quiet):
        self.plt = plt
        self.quiet = quiet
        self.written = []

    def save(self, fig, d, name):
        path = os.path.join(d, name)
        tmp = path + ".tmp"
        fig.tight_layout()
        fig.savefig(tmp, format="png")
        self.plt.close(fig)
        os.replace(tmp, path)
        self.written.append(path)
        if not self.quiet:
            print(path)


def plain_log_axis(ax, which="x"):
    """A log axis labelled 0.1, 0.2, 0.5, 1, 2, 5 ... instead of 10^k powers."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    axis = ax.xaxis if which == "x" else ax.yaxis
    lo, hi = (ax.dataLim.intervalx if which == "x" else ax.dataLim.intervaly)
    (ax.set_xscale if which == "x" else ax.set_yscale)("log")
    # Less than a decade of data (called after the curves are drawn): more labelled ticks.
    ratio = hi / lo if lo > 0 else math.inf
    subs = (1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0) if ratio < 12 else (1.0, 2.0, 5.0) if ratio < 1e4 else (1.0,)
    axis.set_major_locator(LogLocator(base=10, subs=subs))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def stress_mpa(rows, col="platen_stress_Pa"):
    return [r[col] / 1e6 for r in rows]


def positive_pairs(xs, ys):
    return zip(*[(x, y) for x, y in zip(xs, ys) if x > 0 and math.isfinite(y)]) if any(x > 0 for x in xs) else ([], [])


def grains_text(n):
    return f"{n} grain" + ("" if n == 1 else "s")


def monotonic_stress(rows):
    v = [r["platen_stress_Pa"] for r in rows]
    return all(b >= 0.97 * a for a, b in zip(v, v[1:]))


def progress_axis(rows, mode):
    """(x values, axis label, word) for 'against' plots: axial strain for strain-controlled
    loading and wherever the stress falls back (a grain that broke unloads the platen), else
    the platen stress."""
    if mode == "strain_rate" or not monotonic_stress(rows):
        return [100 * r["axial_strain"] for r in rows], "axial strain (%)", "strain"
    return [r["platen_stress_Pa"] / 1e6 for r in rows], "platen stress (MPa)", "stress"


def loading_mode(effective):
    lo = effective.get("loading", {}) if isinstance(effective, dict) else {}
    return lo.get("mode", "stress_ramp") if isinstance(lo, dict) else "stress_ramp"


def scene_type(effective):
    sc = effective.get("scene") if isinstance(effective, dict) else None
    return sc.get("type", "single_grain") if isinstance(sc, dict) else None


SERIES_COLS = ("time_s", "platen_stress_Pa", "axial_strain", "void_ratio", "grains", "breakage_events")


def read_series(d):
    path = os.path.join(d, "series.csv")
    if not os.path.exists(path):
        part = path + ".part"
        if os.path.exists(part):
            path = part
        else:
            raise DataError(f"{path}: missing (a run folder has series.csv)")
    return read_table(path, required=SERIES_COLS)


def fold_not_reached(tables):
    """A level never reached holds the final state again: one curve, labelled with both."""
    if "final" not in tables:
        return tables
    missed = [k for k in tables if "not_reached" in k]
    out = {k: v for k, v in tables.items() if k not in missed}
    if missed:
        out["final"] = [dict(r, _missed=[psd_label(m, tables[m]).split(" (")[0].replace("at ", "") for m in missed])
                        for r in tables["final"]]
    return out


def read_psd(path):
    rows, _ = read_table(path, required=("label", "sieve_diameter_m", "percent_passing_by_mass"),
                         numeric=("platen_stress_Pa", "sieve_diameter_m", "percent_passing_by_mass"))
    tables = {}
    for r in rows:
        tables.setdefault(r["label"], []).append(r)
    return tables


def psd_label(label, rows):
    if label == "initial":
        return "initial"
    if label == "final":
        s = rows[0].get("platen_stress_Pa", math.nan)
        missed = rows[0].get("_missed")
        if missed:
            return f"final ({s / 1e6:.3g} MPa; {', '.join(missed)} not reached)"
        return "final"
    s = rows[0].get("platen_stress_Pa", math.nan)
    stress = f"{s / 1e6:.3g} MPa" if math.isfinite(s) else ""
    if label.startswith("level_"):
        base = f"at {float(label[6:].split('_')[0]) / 1e6:.3g} MPa"
    elif label.startswith("strain_"):
        base = f"at {100 * float(label[7:].split('_')[0]):.3g} % strain"
    else:
        base = label
    if "not_reached" in label:
        return base + f" (not reached; final, {stress})"
    return base


def psd_xy(rows):
    """(sieve diameters in mm, passing %) of one psd.csv table, finest sieve first."""
    rows = sorted(rows, key=lambda r: r["sieve_diameter_m"])
    return [r["sieve_diameter_m"] * 1e3 for r in rows], [r["percent_passing_by_mass"] for r in rows]


def plot_psd_axes(ax, tables, labeller=psd_label, linestyles=None):
    n = len(tables)
    cmap = __import__("matplotlib").colormaps["viridis"]
    for i, (label, rows) in enumerate(tables.items()):
        x, y = psd_xy(rows)
        color = cmap(0.9 * i / max(1, n - 1))
        ax.plot(x, y, marker="o", ms=3, lw=1.6, color=color, label=labeller(label, rows),
                ls=(linestyles[i] if linestyles else "-"))
    plain_log_axis(ax)
    # From the largest sieve that nothing passes in any table (the lower sieves add nothing).
    sieves = sorted({r["sieve_diameter_m"] for rows in tables.values() for r in rows})
    empty = [d for d in sieves if all(r["percent_passing_by_mass"] <= 0 for rows in tables.values()
                                      for r in rows if r["sieve_diameter_m"] == d)]
    lo = max([d for d in empty if d < sieves[-1]], default=sieves[0]) if sieves else None
    if lo and lo > sieves[0]:
        ax.set_xlim(lo * 1e3 / 1.15, sieves[-1] * 1e3 * 1.15)
    ax.set_xlabel("sieve diameter (mm, log scale)")
    ax.set_ylabel("passing by mass (%)")
    ax.set_ylim(-2, 102)


def tables_coincide(tables):
    ref = None
    for rows in tables.values():
        v = sorted((r["sieve_diameter_m"], round(r["percent_passing_by_mass"], 6)) for r in rows)
        if ref is None:
            ref = v
        elif v != ref:
            return False
    return True


def plot_run(F, d):
    plt = F.plt
    summary = read_json(os.path.join(d, "summary.json")) if os.path.exists(os.path.join(d, "summary.json")) else {}
    name = scenario_name(d, summary)
    effective = optional_json(os.path.join(d, "effective_scenario.json"))
    dim = effective.get("dimension", 3) if isinstance(effective, dict) else 3
    series, header = read_series(d)
    mode = loading_mode(effective)
    scene = scene_type(effective)
    s = stress_mpa(series)
    breaks = any(r["breakage_events"] > 0 for r in series) or summary.get("breakage_events", 0) > 0

    # Normal compression line: every sample above 1 % of the peak stress (the settled start is
    # at the settling stress, orders of magnitude below).
    if scene is None and len(series) >= 2:
        pts = [(x, r["void_ratio"]) for x, r in zip(s, series) if x > 0 and r["void_ratio"] > 0]
        if len(pts) >= 2:
            fig, ax = plt.subplots(figsize=(6.4, 4.6))
            monotonic = all(b[0] >= 0.97 * a[0] for a, b in zip(pts, pts[1:]))
            if monotonic:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], lw=1.4, color="tab:blue",
                        marker="." if len(pts) < 60 else None, label="loading")
            else:
                # Strain-controlled or unloading after breakage: the samples, coloured by strain;
                # those of a cell that has (almost) lost its load path, below 0.1 % of the peak,
                # are left out.
                keep = [(x, r) for x, r in zip(s, series) if x > 1e-3 * max(s) and r["void_ratio"] > 0]
                pts = [(x, r["void_ratio"]) for x, r in keep]
                strain = [100 * r["axial_strain"] for _, r in keep]
                sc = ax.scatter([p[0] for p in pts], [p[1] for p in pts], c=strain, s=6, cmap="viridis",
                                label="samples")
                fig.colorbar(sc, ax=ax, label="axial strain (%)")
            settle = effective.get("packing", {}).get("settle", {}) if isinstance(effective, dict) else {}
            e0, s0 = summary.get("void_ratio_initial"), settle.get("stress") if isinstance(settle, dict) else None
            if isinstance(e0, (int, float)) and isinstance(s0, (int, float)) and s0 > 0 and s0 / 1e6 < pts[0][0]:
                # A packing that did not settle (packing_settled 0) is not labelled as settled.
                what = (f"settled packing ({s0 / 1e3:g} kPa)" if summary.get("packing_settled", 1) else
                        f"packing when settling stopped, not settled ({s0 / 1e3:g} kPa asked)")
                ax.plot([s0 / 1e6], [e0], "ks", ms=5, label=what)
                ax.legend(loc="lower left")
            plain_log_axis(ax)
            ax.set_xlabel("platen stress (MPa, log scale)")
            ax.set_ylabel("void ratio e (–)")
            e0 = summary.get("void_ratio_initial")
            ax.set_title(f"{name}: normal compression line" + (f" (e0 = {e0:.3f})" if isinstance(e0, (int, float)) else ""))
            F.save(fig, d, "ncl.png")

    psd_path = os.path.join(d, "psd.csv")
    if os.path.exists(psd_path):
        tables = fold_not_reached(read_psd(psd_path))
        if tables:
            fig, ax = plt.subplots(figsize=(6.4, 4.6))
            plot_psd_axes(ax, tables)
            ax.legend(loc="upper left")
            if len(tables) > 1 and tables_coincide(tables):
                ax.text(0.98, 0.5, "no breakage:\nthe curves coincide", transform=ax.transAxes, ha="right",
                        va="center", color="0.35")
            ax.set_title(f"{name}: particle size distribution")
            F.save(fig, d, "psd.png")

    if breaks and len(series) >= 2 and scene != "single_grain":  # a single grain: load_displacement.png
        xs, xlabel, _ = progress_axis(series, mode)
        x_is_strain = xlabel.startswith("axial")
        per_rows = []
        per = os.path.join(d, "breakage_per_mpa.csv")
        if os.path.exists(per) and not x_is_strain:
            per_rows, _ = read_table(per, required=("stress_from_MPa", "stress_to_MPa", "breakage_events"))
        if per_rows:
            fig, (ax1, axb) = plt.subplots(1, 2, figsize=(10.5, 4.6), gridspec_kw={"width_ratios": [3, 2]})
        else:
            fig, ax1 = plt.subplots(figsize=(6.8, 4.6))
        ax1.plot(xs, [r["grains"] for r in series], color="tab:blue", lw=1.6, label="grains in the engine")
        ax1.plot(xs, [r["breakage_events"] for r in series], color="tab:red", lw=1.6, ls="--",
                 label="breakage events (cumulative)")
        ax1.set_xlabel(xlabel)
        ax1.set_ylabel("count")
        ax1.legend(loc="upper left")
        ax1.set_title(f"{name}: grains and breakage events")
        if per_rows:
            axb.bar([r["stress_from_MPa"] for r in per_rows], [r["breakage_events"] for r in per_rows],
                    width=[0.9 * (r["stress_to_MPa"] - r["stress_from_MPa"]) for r in per_rows], align="edge",
                    color="tab:red", alpha=0.75)
            axb.set_xlabel("platen stress (MPa)")
            axb.set_ylabel("breakage events per MPa")
            axb.set_title("breakage events per 1 MPa of stress")
        F.save(fig, d, "breakage.png")

    # Fractal dimension, when a CSV of the run carries one (column name containing "fractal").
    for fname in ("fractal.csv", "fractal_dimension.csv", "ncl.csv", "series.csv", "psd_fractal.csv"):
        p = os.path.join(d, fname)
        if not os.path.exists(p):
            continue
        with open(p) as f:
            head = [h.strip() for h in f.readline().split(",")]
        fcol = next((h for h in head if "fractal" in h.lower()), None)
        xcol = next((h for h in head if h in ("platen_stress_Pa", "stress_Pa")), None)
        if not fcol or not xcol:
            continue
        rows, _ = read_table(p, required=(xcol, fcol))
        pts = [(r[xcol] / 1e6, r[fcol]) for r in rows if math.isfinite(r[fcol])]
        if len(pts) >= 1:
            fig, ax = plt.subplots(figsize=(6.4, 4.6))
            ax.plot([q[0] for q in pts], [q[1] for q in pts], marker="o", lw=1.4)
            ax.set_xlabel("platen stress (MPa)")
            ax.set_ylabel("fractal dimension D (–)")
            ax.set_title(f"{name}: fractal dimension of the PSD (Zhu & Zhao 2019, eq. 17)")
            F.save(fig, d, "fractal_dimension.png")
        break

    plot_shape(F, d, name, dim, mode, breaks)

    if scene == "single_grain" and len(series) >= 2 and "platen_force_N" in header and "platen_height_m" in header:
        h0 = series[0]["platen_height_m"]
        disp = [h0 - r["platen_height_m"] for r in series]
        # Micrometres for a stiff grain's few-µm travel, millimetres otherwise.
        um = max(abs(x) for x in disp) < 1e-4
        disp = [x * (1e6 if um else 1e3) for x in disp]
        force = [r["platen_force_N"] for r in series]
        fig, ax = plt.subplots(figsize=(6.4, 4.6))
        ax.plot(disp, force, lw=1.6, color="tab:blue")
        ev = [i for i in range(1, len(series)) if series[i]["breakage_events"] > series[i - 1]["breakage_events"]]
        if ev:
            # The last sample before the first breakage: the peak the grain carried.
            i = ev[0] - 1
            crush = summary.get("crushing_force_N")
            what = (f"crushing force {crush:.4g} N (summary.json)" if isinstance(crush, (int, float))
                    else f"last sample before the first breakage, {force[i]:.4g} N")
            ax.plot([disp[i]], [force[i]], "rv", ms=8, label=what)
            ax.legend(loc="upper left")
        ax.set_xlabel("platen displacement (µm)" if um else "platen displacement (mm)")
        ax.set_ylabel("platen force (N)")
        ax.set_title(f"{name}: load–displacement")
        F.save(fig, d, "load_displacement.png")

    if mode == "strain_rate" and len(series) >= 2:
        fig, ax = plt.subplots(figsize=(6.4, 4.6))
        ax.plot([100 * r["axial_strain"] for r in series], s, lw=1.0, color="tab:blue")
        ax.set_xlabel("axial strain (%)")
        ax.set_ylabel("platen stress (MPa)")
        ax.set_title(f"{name}: stress–strain")
        F.save(fig, d, "stress_strain.png")

    rows = product_psd_rows(d)
    if rows:
        fig, ax = plt.subplots(figsize=(6.4, 4.6))
        ax.plot([r["sieve_m"] * 1e3 for r in rows], [r["passing_percent"] for r in rows], marker="o", lw=1.6)
        product_psd_axes(ax)
        ax.set_title(f"{name}: product size distribution")
        F.save(fig, d, "product_psd.png")


def product_psd_rows(d):
    """The rows of DIR/product_psd.csv with a sieve > 0, by sieve size; [] without the file."""
    prod = os.path.join(d, "product_psd.csv")
    if not os.path.exists(prod):
        return []
    rows, _ = read_table(prod, required=("sieve_m", "passing_percent"))
    return sorted([r for r in rows if r["sieve_m"] > 0], key=lambda r: r["sieve_m"])


def product_psd_axes(ax):
    plain_log_axis(ax)
    ax.set_xlabel("sieve size (mm, log scale)")
    ax.set_ylabel("product passing by mass (%)")
    ax.set_ylim(-2, 102)


def spread(values):
    v = [x for x in values if math.isfinite(x)]
    return max(v) - min(v) if v else 0.0


def shapes_vary(first, last, means, invariant, mean_cols, breaks):
    """Whether shape.png has something to show: breakage happened, or the grains differ in a
    descriptor that depends neither on size nor on orientation (sphericity; in 2D circularity
    and aspect ratio) or its mean moves. Identical grains at several sizes (spheres, disks)
    give one value and a flat line: no figure (their Zingg EI and FI scatter only with the
    facets of the mesh)."""
    if breaks:
        return True
    return max([spread(first.get(n, []) + last.get(n, [])) for n in invariant] +
               [spread([r[c] for r in means]) for c in mean_cols]) >= 1e-3


def plot_shape(F, d, name, dim, mode, breaks):
    plt = F.plt
    shape_path = os.path.join(d, "shape.csv")
    means = []
    if os.path.exists(shape_path):
        cols = ("axial_strain", "mean_circularity", "mean_aspect_ratio") if dim == 2 else \
               ("axial_strain", "mean_sphericity", "mean_EI", "mean_FI")
        means, _ = read_table(shape_path, required=cols)
    snaps = vtk_snapshots(d)
    if dim == 2:
        names = ("circularity", "aspect_ratio")
        first = vtk_grain_values(snaps[0], names) if snaps else {}
        last = vtk_grain_values(snaps[1], names) if snaps else {}
        if (not first and len(means) < 2) or not shapes_vary(first, last, means, names,
                                                             ("mean_circularity", "mean_aspect_ratio"), breaks):
            return
        fig, axes = plt.subplots(1, 3, figsize=(13.5, 4.3))
        for ax, n, title, eq in zip(axes, names, ("circularity 4πA/P²", "aspect ratio (best-fit ellipse)"),
                                    ("Harmon et al. 2020, eq. 23", "short / long axis")):
            if first:
                bins = [i / 20 for i in range(21)]
                ax.hist(first[n], bins=bins, alpha=0.55, color="tab:blue", label=f"initial ({grains_text(len(first[n]))})")
                ax.hist(last[n], bins=bins, alpha=0.55, color="tab:red", label=f"final ({grains_text(len(last[n]))})")
                ax.legend(loc="upper left")
            ax.set_xlabel(f"{title} (–)")
            ax.set_ylabel("grains")
            ax.set_title(f"{n.replace('_', ' ')} ({eq})")
        ax = axes[2]
        if len(means) >= 2:
            x = [100 * r["axial_strain"] for r in means]
            ax.plot(x, [r["mean_circularity"] for r in means], label="mean circularity")
            ax.plot(x, [r["mean_aspect_ratio"] for r in means], label="mean aspect ratio")
            ax.set_xlabel("axial strain (%)")
            ax.set_ylabel("mean over grains (–)")
            ax.set_ylim(0, 1.05)
            ax.legend(loc="lower left")
        ax.set_title("means against strain")
        fig.suptitle(f"{name}: grain shape")
        F.save(fig, d, "shape.png")
    else:
        names = ("zingg_ei", "zingg_fi", "sphericity")
        first = vtk_grain_values(snaps[0], names) if snaps else {}
        last = vtk_grain_values(snaps[1], names) if snaps else {}
        if (not first and len(means) < 2) or not shapes_vary(first, last, means, ("sphericity",),
                                                             ("mean_sphericity",), breaks):
            return
        fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11.5, 5.0), gridspec_kw={"width_ratios": [1, 1.2]})
        # Zingg diagram: x = EI = I/L, y = FI = S/I; the classes split at 2/3.
        ax.axvline(2 / 3, color="k", lw=0.8)
        ax.axhline(2 / 3, color="k", lw=0.8)
        box = {"facecolor": "white", "alpha": 0.75, "edgecolor": "none", "pad": 1}
        for (x, y, t, ha, va) in ((0.68, 1.0, "equant", "left", "top"), (1.0, 0.01, "oblate (disc)", "right", "bottom"),
                                  (0.01, 1.0, "prolate (rod)", "left", "top"), (0.65, 0.01, "bladed", "right", "bottom")):
            ax.text(x, y, t, ha=ha, va=va, color="0.35", fontsize=9, bbox=box, zorder=1)
        if first:
            ax.scatter(last["zingg_ei"], last["zingg_fi"], s=12, alpha=0.6, color="tab:red", marker="^",
                       label=f"final ({grains_text(len(last['zingg_ei']))})", zorder=2)
            ax.scatter(first["zingg_ei"], first["zingg_fi"], s=28, alpha=0.8, facecolor="none", edgecolor="tab:blue",
                       label=f"initial ({grains_text(len(first['zingg_ei']))})", zorder=3)
        if len(means) >= 2:
            ax.plot([r["mean_EI"] for r in means], [r["mean_FI"] for r in means], color="k", lw=1.2,
                    label="mean, start → end")
            ax.plot([means[-1]["mean_EI"]], [means[-1]["mean_FI"]], "k>", ms=7)
        ax.set_xlim(0, 1.02)
        ax.set_ylim(0, 1.02)
        ax.set_aspect("equal")
        ax.set_xlabel("elongation EI = I/L (–)")
        ax.set_ylabel("flatness FI = S/I (–)")
        ax.legend(loc="lower left", bbox_to_anchor=(0.0, 0.06))
        ax.set_title("Zingg diagram")
        if len(means) >= 2:
            x, xlabel, word = progress_axis(means, mode)
            ax2.plot(x, [r["mean_sphericity"] for r in means], label="mean sphericity (Wadell)")
            ax2.plot(x, [r["mean_EI"] for r in means], label="mean EI")
            ax2.plot(x, [r["mean_FI"] for r in means], label="mean FI")
            ax2.set_xlabel(xlabel)
            ax2.set_ylabel("mean over grains (–)")
            ax2.set_ylim(0, 1.05)
            ax2.legend(loc="lower left")
            ax2.set_title("means against " + word)
        else:
            ax2.axis("off")
        fig.suptitle(f"{name}: grain shape")
        F.save(fig, d, "shape.png")


def run_folders(d):
    """(label, folder) of the runs of a compare/sweep folder, in comparison.csv's order."""
    path = os.path.join(d, "comparison.csv")
    rows, header = read_table(path, required=("folder", "status"), numeric=())
    axes = header[:header.index("folder")]
    out = []
    for r in rows:
        label = ", ".join(f"{a.split('.')[-1]}={r[a]:g}" if isinstance(r[a], float) else f"{a.split('.')[-1]}={r[a]}"
                          for a in axes) or str(r["folder"])
        if r["status"] != "ok":
            label += f" ({r['status']})"
        out.append((label, os.path.join(d, r["folder"])))
    return out


def plot_compare(F, d, title):
    plt = F.plt
    runs = run_folders(d)
    data = []
    for label, f in runs:
        if os.path.exists(os.path.join(f, "series.csv")) or os.path.exists(os.path.join(f, "series.csv.part")):
            series, header = read_series(f)
            eff = optional_json(os.path.join(f, "effective_scenario.json"))
            data.append((label, f, series, eff))
    if not data:
        raise DataError(f"{os.path.join(d, 'comparison.csv')}: none of its run folders holds a series.csv")
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    styles = ["-", "--", "-.", ":"]

    def overlay(fname, ytitle, xy, xlog=False, xlabel="platen stress (MPa)", what="", points=False):
        fig, ax = plt.subplots(figsize=(7.2, 4.8))
        drawn = 0
        for i, (label, f, series, eff) in enumerate(data):
            x, y = xy(series)
            if len(x) >= 2 and points:  # samples that go back and forth: no connecting line
                ax.plot(x, y, ls="none", marker="o", ms=2.5, alpha=0.7, color=colors[i % len(colors)], label=label)
                drawn += 1
            elif len(x) >= 2:
                ax.plot(x, y, lw=1.5, color=colors[i % len(colors)], ls=styles[(i // len(colors)) % 4], label=label)
                drawn += 1
        if drawn == 0:
            plt.close(fig)
            return
        if xlog:
            plain_log_axis(ax)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ytitle)
        ax.legend(loc="best")
        ax.set_title(f"{title}: {what}")
        F.save(fig, d, fname)

    strain = all(loading_mode(e) == "strain_rate" for _, _, _, e in data)
    scene = any(scene_type(e) for _, _, _, e in data)

    def ncl(series):
        smax = max([r["platen_stress_Pa"] for r in series] + [0])
        pts = [(r["platen_stress_Pa"] / 1e6, r["void_ratio"]) for r in series
               if r["platen_stress_Pa"] > 1e-3 * smax and r["void_ratio"] > 0]
        return [p[0] for p in pts], [p[1] for p in pts]

    if not scene:
        overlay("compare_ncl.png", "void ratio e (–)", ncl, xlog=True, xlabel="platen stress (MPa, log scale)",
                what="normal compression lines", points=not all(monotonic_stress(s) for _, _, s, _ in data))
    if any(r["breakage_events"] > 0 for _, _, s, _ in data for r in s):
        if strain:
            overlay("compare_breakage.png", "grains in the engine",
                    lambda s: ([100 * r["axial_strain"] for r in s], [r["grains"] for r in s]),
                    xlabel="axial strain (%)", what="grain count")
        else:
            overlay("compare_breakage.png", "breakage events (cumulative)",
                    lambda s: ([r["platen_stress_Pa"] / 1e6 for r in s], [r["breakage_events"] for r in s]),
                    what="breakage events against stress")
    if any(scene_type(e) == "single_grain" for _, _, _, e in data):
        def load_disp(s):
            if not s or "platen_height_m" not in s[0] or "platen_force_N" not in s[0]:
                return [], []
            return [1e6 * (s[0]["platen_height_m"] - r["platen_height_m"]) for r in s], [r["platen_force_N"] for r in s]
        overlay("compare_load_displacement.png", "platen force (N)", load_disp, xlabel="platen displacement (µm)",
                what="load–displacement")
    if strain:
        compare_stress_strain(F, d, title, data, colors, styles)
    compare_psd_levels(F, d, title, data, colors, styles)
    compare_shape(F, d, title, data, colors, styles)
    # Final PSD of each run (initial of the first run, dotted, for reference).
    finals, initial = {}, None
    for label, f, _, _ in data:
        p = os.path.join(f, "psd.csv")
        if os.path.exists(p):
            t = read_psd(p)
            key = "final" if "final" in t else list(t)[-1]
            finals[label] = t[key]
            if initial is None and "initial" in t:
                initial = t["initial"]
    if finals:
        fig, ax = plt.subplots(figsize=(7.2, 4.8))
        if initial:
            ax.plot(*psd_xy(initial), color="0.5", ls=":", lw=1.5, label="initial")
        for i, (label, rows) in enumerate(finals.items()):
            # The stress each run ended at: runs stopped early are not shown as at the full load.
            s = rows[0].get("platen_stress_Pa", math.nan) if rows else math.nan
            at = f" ({s / 1e6:.3g} MPa)" if math.isfinite(s) else ""
            ax.plot(*psd_xy(rows),
                    color=colors[i % len(colors)], ls=styles[(i // len(colors)) % 4], marker="o", ms=3, lw=1.5,
                    label=f"{label}, final{at}")
        plain_log_axis(ax)
        ax.set_xlabel("sieve diameter (mm, log scale)")
        ax.set_ylabel("passing by mass (%)")
        ax.set_ylim(-2, 102)
        ax.legend(loc="upper left")
        ax.set_title(f"{title}: final particle size distributions")
        F.save(fig, d, "compare_psd.png")
    # Open scenes: the product of each run (Harmon et al. 2020 Fig. 8 for the jaw crusher).
    products = [(label, product_psd_rows(f)) for label, f, _, _ in data]
    products = [(label, rows) for label, rows in products if rows]
    if products:
        fig, ax = plt.subplots(figsize=(7.2, 4.8))
        for i, (label, rows) in enumerate(products):
            ax.plot([r["sieve_m"] * 1e3 for r in rows], [r["passing_percent"] for r in rows], marker="o", ms=3,
                    lw=1.5, color=colors[i % len(colors)], ls=styles[(i // len(colors)) % 4], label=label)
        product_psd_axes(ax)
        ax.legend(loc="upper left")
        ax.set_title(f"{title}: product size distributions")
        F.save(fig, d, "compare_product_psd.png")


def compare_stress_strain(F, d, title, data, colors, styles):
    """Platen stress and void ratio against axial strain, every run overlaid."""
    fig, (a1, a2) = F.plt.subplots(1, 2, figsize=(12.4, 4.6))
    for i, (label, _, s, _) in enumerate(data):
        x = [100 * r["axial_strain"] for r in s]
        kw = dict(lw=1.3, color=colors[i % len(colors)], ls=styles[(i // len(colors)) % 4], label=label)
        a1.plot(x, [r["platen_stress_Pa"] / 1e6 for r in s], **kw)
        a2.plot(x, [r["void_ratio"] for r in s], **kw)
    for ax, y in ((a1, "platen stress (MPa)"), (a2, "void ratio e (–)")):
        ax.set_xlabel("axial strain (%)")
        ax.set_ylabel(y)
        ax.legend(loc="best")
    fig.suptitle(f"{title}: stress and void ratio against strain")
    F.save(fig, d, "compare_stress_strain.png")


def reached_levels(tables):
    """The psd.csv levels (stress or strain) that at least one run reached, in order of first
    appearance (a table labelled not_reached is the final state, not the level)."""
    levels = []
    for t in tables:
        levels += [k for k in t if k.startswith(("level_", "strain_")) and "not_reached" not in k and k not in levels]
    return levels


def compare_psd_levels(F, d, title, data, colors, styles):
    """One panel per psd.csv level a run reached (psd_at_stress / psd_at_strain), the runs that
    reached it overlaid on the initial distribution (dotted), the others named as not reaching
    it: how each run's grading evolves, side by side."""
    runs = [(label, read_psd(os.path.join(f, "psd.csv"))) for label, f, _, _ in data
            if os.path.exists(os.path.join(f, "psd.csv"))]
    levels = reached_levels([t for _, t in runs])
    if not levels:
        return
    fig, axes = F.plt.subplots(1, len(levels), figsize=(4.6 * len(levels), 4.4), squeeze=False)
    initial = runs[0][1].get("initial")
    for ax, level in zip(axes[0], levels):
        if initial:
            ax.plot(*psd_xy(initial), color="0.5", ls=":", lw=1.5, label="initial")
        for i, (label, t) in enumerate(runs):
            if level not in t:
                continue
            ax.plot(*psd_xy(t[level]),
                    color=colors[i % len(colors)], ls=styles[(i // len(colors)) % 4], marker="o", ms=2.5, lw=1.3,
                    label=label)
        missing = [label for label, t in runs if level not in t]
        if missing:
            ax.text(0.98, 0.03, "not reached:\n" + "\n".join(missing), transform=ax.transAxes, ha="right",
                    va="bottom", fontsize=7, color="0.35")
        plain_log_axis(ax)
        ax.set_xlabel("sieve diameter (mm, log scale)")
        ax.set_ylabel("passing by mass (%)")
        ax.set_ylim(-2, 102)
        ax.set_title(psd_label(level, next(t[level] for _, t in runs if level in t)))
        ax.legend(loc="upper left", fontsize=8)
    fig.suptitle(f"{title}: particle size distributions")
    F.save(fig, d, "compare_psd_levels.png")


def compare_shape(F, d, title, data, colors, styles):
    """The grains' mean shape descriptors (shape.csv) against strain or stress, runs overlaid."""
    means = []
    for label, f, _, eff in data:
        path = os.path.join(f, "shape.csv")
        if not os.path.exists(path):
            return
        dim = eff.get("dimension", 3) if isinstance(eff, dict) else 3
        cols = ("mean_circularity", "mean_aspect_ratio") if dim == 2 else ("mean_sphericity", "mean_EI", "mean_FI")
        rows, _ = read_table(path, required=("axial_strain", "platen_stress_Pa") + cols,
                             numeric=("axial_strain", "platen_stress_Pa"))
        means.append((label, rows, cols))
    if not means or len({m[2] for m in means}) != 1 or all(len(m[1]) < 2 for m in means):
        return
    strain = all(loading_mode(e) == "strain_rate" for _, _, _, e in data)
    cols = means[0][2]
    fig, axes = F.plt.subplots(1, len(cols), figsize=(5.6 * len(cols), 4.4), squeeze=False)
    names = {"mean_circularity": "mean circularity 4πA/P² (Harmon et al. 2020, eq. 23)",
             "mean_aspect_ratio": "mean aspect ratio", "mean_sphericity": "mean sphericity",
             "mean_EI": "mean elongation index EI", "mean_FI": "mean flatness index FI"}
    for ax, c in zip(axes[0], cols):
        for i, (label, rows, _) in enumerate(means):
            pts = [(100 * r["axial_strain"] if strain else r["platen_stress_Pa"] / 1e6, r[c]) for r in rows
                   if isinstance(r[c], float) and math.isfinite(r[c])]  # empty where no grain has a value
            ax.plot([p[0] for p in pts], [p[1] for p in pts], lw=1.3, color=colors[i % len(colors)],
                    ls=styles[(i // len(colors)) % 4], label=label)
        ax.set_xlabel("axial strain (%)" if strain else "platen stress (MPa)")
        ax.set_ylabel(names[c])
        ax.legend(loc="best", fontsize=8)
    fig.suptitle(f"{title}: grain shape")
    F.save(fig, d, "compare_shape.png")


def plot_sweep(F, d, title):
    plt = F.plt
    path = os.path.join(d, "sweep.csv")
    rows, header = read_table(path, required=("folder", "status", "reference", "wall_seconds", "error", "on_front"),
                              numeric=())
    params = header[:header.index("folder")]
    pts = []
    for n, r in enumerate(rows, start=2):
        if r["status"] != "ok":
            continue
        try:
            cost = float(r["wall_seconds"])
            err = float(r["error"]) if r["error"] != "" else math.nan
            ref = float(r["reference"]) == 1
            front = float(r["on_front"]) == 1
        except ValueError:
            raise DataError(f"{path}: line {n}: wall_seconds, error, reference or on_front is not a number")
        label = ", ".join(f"{r[p]:g}" if isinstance(r[p], float) else str(r[p]) for p in params) or str(r["folder"])
        pts.append((cost, err, ref, front, label))
    if not pts:
        raise DataError(f"{path}: no setting ran to the end (status ok)")
    fig, ax = plt.subplots(figsize=(7.2, 5.0))
    floor = None
    finite = [p[1] for p in pts if math.isfinite(p[1]) and p[1] > 0]
    # The reference has error 0: drawn at the bottom of a log axis, marked as the reference.
    logy = bool(finite) and max(finite) / min(finite) > 20
    if logy:
        floor = min(finite) / 3
    def ey(e):
        return 100 * (floor if (logy and e <= 0) else e)
    front = sorted([p for p in pts if p[3] and math.isfinite(p[1])], key=lambda p: p[0])
    if front:
        ax.plot([p[0] for p in front], [ey(p[1]) for p in front], color="tab:red", lw=1.2, zorder=1,
                label="error–cost front")
    for cost, err, ref, on, label in pts:
        if not math.isfinite(err):
            continue
        ax.scatter([cost], [ey(err)], s=55 if on else 35, marker="*" if ref else "o",
                   facecolor="tab:red" if on else "white", edgecolor="tab:red" if on else "0.3", zorder=2)
        ax.annotate(label + (" (reference)" if ref else ""), (cost, ey(err)), textcoords="offset points",
                    xytext=(6, 4), fontsize=8)
    missing = [p[4] for p in pts if not math.isfinite(p[1])]
    # The reference that did not finish leaves every error empty: say so, not "never reached".
    failed_ref = [r for r in rows if str(r["reference"]).strip() in ("1", "1.0") and r["status"] != "ok"]
    if failed_ref:
        r = failed_ref[0]
        label = ", ".join(f"{r[p]:g}" if isinstance(r[p], float) else str(r[p]) for p in params) or str(r["folder"])
        ax.text(0.5, 0.5, f"the reference setting ({label}) did not finish ({r['status']}):\nno errors to compare; "
                "see pareto.md\nsettings that ran: " + ", ".join(f"{p[4]} ({p[0]:.3g} s)" for p in pts),
                transform=ax.transAxes, fontsize=9, color="0.25", ha="center", va="center")
        ax.set_xticks([])
        ax.set_yticks([])
    elif missing:
        ax.text(0.02, 0.02, "no finite error (a metric the reference has was never reached): " + ", ".join(missing),
                transform=ax.transAxes, fontsize=8, color="0.35", va="bottom")
    costs = [p[0] for p in pts if p[0] > 0 and math.isfinite(p[1])]
    if costs and max(costs) / min(costs) > 20:
        plain_log_axis(ax)
    if logy:
        plain_log_axis(ax, "y")
    ax.scatter([], [], s=55, facecolor="tab:red", edgecolor="tab:red", label="on the front")
    ax.scatter([], [], s=35, facecolor="white", edgecolor="0.3", label="dominated")
    ax.set_xlabel("wall time (s" + (", log scale)" if ax.get_xscale() == "log" else ")"))
    ax.set_ylabel("largest relative error of the metrics (%" + (", log scale)" if logy else ")"))
    ax.legend(loc="upper right")
    ax.set_title(f"{title}: error against cost ({', '.join(params)})")
    F.save(fig, d, "pareto.png")


def main(argv):
    args = [a for a in argv[1:] if a != "--quiet"]
    quiet = "--quiet" in argv[1:]
    if len(args) != 1 or args[0] in ("-h", "--help"):
        print(__doc__.strip().split("\n\n")[1], file=sys.stderr)
        return EXIT_DATA
    d = args[0]
    if not os.path.isdir(d):
        print(f"{d}: not a folder", file=sys.stderr)
        return EXIT_DATA
    plt = setup_matplotlib()
    if plt is None:
        print("matplotlib is not importable by " + sys.executable + " (Debian: apt-get install python3-matplotlib)",
              file=sys.stderr)
        return EXIT_NO_MATPLOTLIB
    F = Figures(plt, quiet)
    try:
        is_sweep = os.path.exists(os.path.join(d, "sweep.csv"))
        is_compare = os.path.exists(os.path.join(d, "comparison.csv"))
        if is_sweep or is_compare:
            base = os.path.basename(os.path.normpath(d))
            md = os.path.join(d, "comparison.md")
            if os.path.exists(md):  # "# crumble compare: NAME (FILE)"
                with open(md) as f:
                    first = f.readline().strip()
                if ":" in first:
                    base = first.split(":", 1)[1].split("(")[0].strip() or base
            if is_sweep:
                plot_sweep(F, d, base)
            plot_compare(F, d, base)
        elif os.path.exists(os.path.join(d, "series.csv")) or os.path.exists(os.path.join(d, "series.csv.part")):
            plot_run(F, d)
        else:
            raise DataError(f"{d}: no crumble output here (expected series.csv of a run, comparison.csv of a "
                            "compare or sweep.csv of a sweep)")
    except DataError as e:
        print(str(e), file=sys.stderr)
        return EXIT_DATA
    if not F.written:
        print(f"{d}: nothing to plot (the run wrote no sample)", file=sys.stderr)
        return EXIT_DATA
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
