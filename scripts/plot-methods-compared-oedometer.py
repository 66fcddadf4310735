#!/usr/bin/env python3
"""Figures of docs/methods-compared.md, the quick Zhu & Zhao packing: void ratio and breakage
events against platen stress, and the grading at two stress levels, one curve per run.

    python3 scripts/plot-methods-compared-oedometer.py --img-dir docs/img \
        "Zhu & Zhao 2019=OUT/method=zhu_zhao_2019" "Harmon et al. 2020=OUT/method=harmon_2020" ...

Each run folder is one `crumble run` or one combination of `crumble compare`: series.csv
(platen_stress_Pa, void_ratio), events.csv (outcome, platen_stress_Pa) and psd.csv (label, platen_stress_Pa,
sieve_diameter_m, percent_passing_by_mass). Both panels of the first figure read the commanded
platen stress (series.csv target_stress_Pa; lsdem's measured stress oscillates about it). A PSD
level a run did not reach is labelled with the measured stress it stopped at, never with the
level. Needs matplotlib (Debian: python3-matplotlib).
"""
import argparse
import bisect
import csv
import os
import sys


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def series(run):
    """Void ratio at each series sample against the commanded platen stress: (MPa, e)."""
    rows = read_rows(os.path.join(run, "series.csv"))
    return [float(r["target_stress_Pa"]) / 1e6 for r in rows], [float(r["void_ratio"]) for r in rows]


def commanded(run):
    """The commanded platen stress (MPa) at a time, interpolated between series samples."""
    rows = read_rows(os.path.join(run, "series.csv"))
    t = [float(r["time_s"]) for r in rows]
    s = [float(r["target_stress_Pa"]) / 1e6 for r in rows]

    def at(x):
        i = bisect.bisect_left(t, x)
        if i == 0:
            return s[0]
        if i >= len(t):
            return s[-1]
        return s[i - 1] + (s[i] - s[i - 1]) * (x - t[i - 1]) / (t[i] - t[i - 1])
    return at


def splits(run):
    """Cumulative breakage events (events.csv rows with outcome split) against the commanded
    platen stress at their check: (MPa, count)."""
    at = commanded(run)
    rows = [r for r in read_rows(os.path.join(run, "events.csv")) if r["outcome"] == "split"]
    return [at(float(r["time_s"])) for r in rows], list(range(1, len(rows) + 1))


def psd_curves(run, level):
    """The PSD curve whose label names `level` (Pa), else the final one: (title, d mm, % passing)."""
    rows = read_rows(os.path.join(run, "psd.csv"))
    want = "level_%g" % level
    label = next((r["label"] for r in rows if r["label"] == want), "final")
    pick = [r for r in rows if r["label"] == label]
    stress = float(pick[0]["platen_stress_Pa"]) / 1e6
    d = [float(r["sieve_diameter_m"]) * 1e3 for r in pick]
    p = [float(r["percent_passing_by_mass"]) for r in pick]
    return "%.2f MPa" % stress, d, p


def parse_runs(items):
    runs = []
    for item in items:
        if "=" not in item:
            sys.exit("expected LABEL=FOLDER, got %r" % item)
        label, folder = item.split("=", 1)
        if not os.path.isfile(os.path.join(folder, "series.csv")):
            sys.exit("%s: no series.csv (an unfinished run writes series.csv.part)" % folder)
        runs.append((label, folder))
    return runs


def draw_ncl(runs, out):
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    for label, run in runs:
        s, e = series(run)
        a.plot(s, e, marker="o", markersize=3, label=label)
        b.plot(*splits(run), drawstyle="steps-post", label=label)
    a.set_xlabel("commanded platen stress (MPa)")
    a.set_ylabel("void ratio")
    a.set_title("(a) compression (series samples)")
    b.set_xlabel("commanded platen stress (MPa)")
    b.set_ylabel("breakage events (cumulative)")
    b.set_title("(b) breakage")
    a.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def draw_psd(runs, levels, out):
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(levels), figsize=(5 * len(levels), 4), squeeze=False)
    for ax, level in zip(axes[0], levels):
        for label, run in runs:
            at, d, p = psd_curves(run, level)
            ax.plot(d, p, drawstyle="steps-post", label="%s (at %s)" % (label, at))
        ax.set_xscale("log")
        ax.set_xlim(0.2, 2.5)
        ax.set_xticks([0.2, 0.3, 0.5, 1, 1.5, 2])
        ax.set_xticklabels(["0.2", "0.3", "0.5", "1", "1.5", "2"])
        ax.set_xlabel("sieve diameter (mm)")
        ax.set_ylabel("passing by mass (%)")
        ax.set_title("grading at %g MPa, or where the run stopped" % (level / 1e6))
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", help="LABEL=FOLDER")
    ap.add_argument("--img-dir", default=".")
    ap.add_argument("--levels", default="5e6,1e7", help="PSD levels in Pa (psd.csv labels level_X)")
    a = ap.parse_args()
    runs = parse_runs(a.runs)
    try:
        import matplotlib
        matplotlib.use("Agg")
    except ImportError:
        sys.exit("matplotlib is missing (Debian: apt-get install python3-matplotlib)")
    levels = [float(x) for x in a.levels.split(",")]
    draw_ncl(runs, os.path.join(a.img_dir, "methods-compared-oedometer-ncl.png"))
    draw_psd(runs, levels, os.path.join(a.img_dir, "methods-compared-oedometer-psd.png"))


if __name__ == "__main__":
    main()
