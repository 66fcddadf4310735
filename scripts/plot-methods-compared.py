#!/usr/bin/env python3
"""The 2 mm grain on every engine, breakage model and fragment builder (docs/methods-compared.md).

    python3 scripts/plot-methods-compared.py COMPARE_DIR [--every-step DIR] [--img-dir docs/img]

COMPARE_DIR is what

    crumble compare scenarios/single_grain_pd.json --vary engine.type=bullet,ode,lsdem \\
        --vary breakage.type=peridynamics,stress --vary fragments.type=alpha_shape,level_set --out COMPARE_DIR

wrote; --every-step DIR (optional) what the same compare with `--set breakage.type=stress
--set schedule.every_steps=1` and `--vary engine.type=bullet,ode,lsdem` wrote; --also DIR (any
number) further compares of that kind, printed only. Reads each run
folder's summary.json, events.csv, series.csv and load_displacement.csv, prints the tables of
docs/methods-compared.md (Markdown) on stdout and draws into --img-dir:

  methods-compared-single-grain-force.png   crushing force per combination (bars), the platen
      force the loading commanded at the breaking check (dots), the stress model checked at
      every step (diamonds), Zhu & Zhao 2019's value (Fig. 9) and the stress model's closed form
  methods-compared-single-grain-curves.png  (a) platen force against platen displacement per
      engine, with Hertz's law for the grain's material; (b) lsdem's platen and floor forces
      around the split of the stress model, against the commanded force

The fragment builder acts only after the split: the script checks that the two builders' series
agree up to it and draws one curve per engine and model. Needs matplotlib (Debian:
python3-matplotlib); without it the tables are still printed (exit status 3).
"""
import argparse
import csv
import json
import math
import os
import sys

ENGINES = ["bullet", "ode", "lsdem"]
MODELS = ["peridynamics", "stress"]
BUILDERS = ["alpha_shape", "level_set"]
PAPER_FORCE_N = 180.0  # Zhu & Zhao 2019 §4.2, Fig. 9: "a crushing force of about 180 N" (G_c0 = 30 J/m², d = 2 mm)


def read_csv(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def load_run(folder):
    s = json.load(open(os.path.join(folder, "summary.json")))
    return {"summary": s, "events": read_csv(os.path.join(folder, "events.csv")),
            "series": read_csv(os.path.join(folder, "series.csv")),
            "ld": read_csv(os.path.join(folder, "load_displacement.csv")), "folder": folder}


def load_by_engine(out):
    runs = {}
    for row in read_csv(os.path.join(out, "comparison.csv")):
        if row["status"] == "ok":
            runs[row["engine.type"]] = load_run(os.path.join(out, row["folder"]))
    return runs


def print_by_engine(title, runs):
    print()
    print(f"{title}:")
    print()
    print("| engine | crushing force N | von Mises at it MPa | commanded platen force N | steps | analyses |")
    print("|---|---|---|---|---|---|")
    for eng in ENGINES:
        if eng in runs:
            f = figures(runs[eng])
            print(f"| {eng} | {f['force']:.2f} | {f['eq_stress'] / 1e6:.2f} | {f['commanded_force']:.1f} | {f['steps']} "
                  f"| {f['analyses']} |")


def load_compare(out):
    runs = {}
    for row in read_csv(os.path.join(out, "comparison.csv")):
        key = tuple(row.get(k, "") for k in ("engine.type", "breakage.type", "fragments.type"))
        if row["status"] != "ok":
            print(f"note: {row['folder']} {row['status']}: {row['reason']}", file=sys.stderr)
            continue
        runs[key] = load_run(os.path.join(out, row["folder"]))
    return runs


def num(r, k):
    return float(r[k]) if r.get(k, "") not in ("", None) else float("nan")


def platen_area(series):
    for r in series:
        if num(r, "platen_stress_Pa") > 0 and num(r, "platen_force_N") > 0:
            return num(r, "platen_force_N") / num(r, "platen_stress_Pa")
    raise ValueError("no loaded sample in series.csv")


def at_step(series, step, key):
    """`key` of the series at `step`: the sample there, else linear between the two around it."""
    prev = None
    for r in series:
        s = int(r["step"])
        if s == step:
            return num(r, key)
        if s > step and prev is not None:
            s0 = int(prev["step"])
            w = (step - s0) / (s - s0)
            return (1 - w) * num(prev, key) + w * num(r, key)
        prev = r
    return num(prev, key) if prev else float("nan")


def split_event(run):
    for e in run["events"]:
        if e["outcome"] == "split":
            return e
    return None


def figures(run):
    """The numbers of one run for the tables and the plots."""
    s, e = run["summary"], split_event(run)
    area = platen_area(run["series"])
    d = s["diameter_m"]
    parent = math.pi * d ** 3 / 6
    vols = [float(v) for v in e["child_volumes_m3"].split(";")] if e else []
    step = int(e["step"]) if e else -1
    mi, mf, mr = s["mass_initial_kg"], s["mass_final_kg"], s["mass_removed_kg"]
    return {
        "force": s.get("crushing_force_N", float("nan")),
        "eq_stress": s.get("crushing_stress_Pa", float("nan")),
        "platen_force": num(e, "platen_stress_Pa") * area if e else float("nan"),
        "commanded_force": at_step(run["series"], step, "target_stress_Pa") * area if e else float("nan"),
        "platen_stress": num(e, "platen_stress_Pa") if e else float("nan"),
        "strain": at_step(run["series"], step, "axial_strain") if e else float("nan"),
        "first_bond_force": num(e, "first_break_force_N") if e and "first_break_force_N" in e else float("nan"),
        "fragments": len(vols),
        "largest": max(vols) / parent if vols else float("nan"),
        "removed": mr / mi,
        "budget": (mf + mr - mi) / mi,
        "fallbacks": s.get("fragment_fallbacks", 0),
        "method": e["fragment_method"] if e else "",
        "analyses": s.get("analyses", 0),
        "unbalanced": s.get("screening_unbalanced_force", 0),
        "steps": s["steps"],
        "wall": s["wall_seconds"],
        "times": s.get("time_breakdown_s", {}),
        "diameter": d,
    }


def closed_form_force(strength_pa, d):
    """Force of a sphere between two plates at which σ̄ (Harmon et al. 2020, eq. 5) reaches the strength.

    Two opposite forces F at x = ±d/2 along the load axis: σ̄_zz = −(2·(d/2)·F)/V = −6F/(πd²),
    the other components 0, so σ1 = σ2 = 0, σ3 = −6F/(πd²) and von Mises = |σ3|."""
    return math.pi * d * d * strength_pa / 6


SERIES_COLUMNS = ("step", "platen_force_N", "floor_force_N", "platen_height_m")


def same_series(a, b, rows):
    """The first `rows` samples of two runs' series.csv agree (step, forces, platen height)."""
    return [[r[c] for c in SERIES_COLUMNS] for r in a["series"][:rows]] == \
        [[r[c] for c in SERIES_COLUMNS] for r in b["series"][:rows]]


def check_same_runs(runs):
    """The builders act only on the split that ends a run, and an engine's two models run the
    same steps until the stress model's split: say so on stderr where that does not hold."""
    for eng in ENGINES:
        for mod in MODELS:
            a, b = runs.get((eng, mod, BUILDERS[0])), runs.get((eng, mod, BUILDERS[1]))
            if a and b and not same_series(a, b, len(a["series"])):
                print(f"note: {eng} {mod}: the builders' series differ", file=sys.stderr)
        a, b = runs.get((eng, "stress", BUILDERS[0])), runs.get((eng, "peridynamics", BUILDERS[0]))
        if a and b and not same_series(a, b, len(a["series"]) - 1):
            print(f"note: {eng}: the two models' series differ before the stress model's split", file=sys.stderr)


def print_table(runs, header, cells):
    """One Markdown row per combination that ran: engine, model, builder, then cells(figures)."""
    print("| engine | model | builder | " + " | ".join(header) + " |")
    print("|---|---|---|" + "---|" * len(header))
    for eng in ENGINES:
        for mod in MODELS:
            for bld in BUILDERS:
                run = runs.get((eng, mod, bld))
                if run:
                    print(f"| {eng} | {mod} | {bld} | " + " | ".join(cells(figures(run))) + " |")


def print_tables(runs, every_step, strength, d):
    print_table(runs, ["crushing force N", "platen force at the check N", "commanded N", "platen stress MPa",
                       "axial strain %", "fragments", "largest fragment %", "removed %", "fallbacks", "wall s"],
                lambda f: [f"{f['force']:.1f}", f"{f['platen_force']:.1f}", f"{f['commanded_force']:.1f}",
                           f"{f['platen_stress'] / 1e6:.2f}", f"{100 * f['strain']:.3f}", f"{f['fragments']}",
                           f"{100 * f['largest']:.1f}", f"{100 * f['removed']:.2f}", f"{f['fallbacks']}",
                           f"{f['wall']:.1f}"])
    print()
    print_table(runs, ["steps", "analyses", "screened out unbalanced", "analyses s", "fragments s", "engine s",
                       "output s", "mass budget (final + removed − initial) / initial"],
                lambda f: [f"{f['steps']}", f"{f['analyses']}", f"{int(f['unbalanced'])}"] +
                [f"{f['times'].get(k, 0):.2f}" for k in ("analyses", "fragments", "engine", "output")] +
                [f"{f['budget']:.1e}"])
    print()
    print(f"closed form of the stress model: F = π d² σ0 / 6 = {closed_form_force(strength, d):.2f} N "
          f"(σ0 = {strength / 1e6:g} MPa, d = {d * 1e3:g} mm)")
    if every_step:
        print_by_engine("the stress model checked at every step", every_step)


def save(fig, path):
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)
    print(f"wrote {path}", file=sys.stderr)


def plot_force(plt, runs, every_step, strength, d, path):
    fig, ax = plt.subplots(figsize=(8.4, 5.6))
    combos = [(m, b) for m in MODELS for b in BUILDERS]
    colours = {("peridynamics", "alpha_shape"): "#1f77b4", ("peridynamics", "level_set"): "#6baed6",
               ("stress", "alpha_shape"): "#d62728", ("stress", "level_set"): "#fc9272"}
    width = 0.2
    for i, eng in enumerate(ENGINES):
        for j, (mod, bld) in enumerate(combos):
            run = runs.get((eng, mod, bld))
            if not run:
                continue
            f = figures(run)
            x = i + (j - 1.5) * width
            ax.bar(x, f["force"], width * 0.92, color=colours[(mod, bld)], label=f"{mod} + {bld}" if i == 0 else None)
            ax.text(x, f["force"] + 2, f"{f['force']:.1f}", ha="center", va="bottom", fontsize=7)
            ax.plot(x, f["commanded_force"], "o", color="black", ms=4,
                    label="commanded platen force at the breaking check" if i == 0 and j == 0 else None)
            es = every_step.get(eng)
            if mod == "stress" and es:
                ax.plot(x, figures(es)["force"], "D", color="white", mec="black", ms=5,
                        label="stress model checked at every step" if i == 0 and j == 2 else None)
    ax.axhline(PAPER_FORCE_N, color="#1f77b4", ls="--", lw=1, label="Zhu & Zhao 2019, Fig. 9: about 180 N")
    fc = closed_form_force(strength, d)
    ax.axhline(fc, color="#d62728", ls=":", lw=1.2,
               label=f"stress model's closed form π d² σ0 / 6 = {fc:.1f} N (σ0 = {strength / 1e6:g} MPa)")
    ax.set_xticks(range(len(ENGINES)))
    ax.set_xticklabels(ENGINES)
    ax.set_xlim(-0.5, 2.5)
    ax.set_ylim(0, 200)
    ax.set_ylabel("crushing force (N)")
    ax.set_title("The 2 mm grain of single_grain_pd: crushing force per engine, model and builder", fontsize=10)
    ax.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.07), ncol=2)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    save(fig, path)


def hertz_curve(run, n=60):
    """Platen approach of a sphere between two rigid plates by Hertz: 2·(9F²/(16 R E*²))^(1/3)."""
    scen = json.load(open(os.path.join(run["folder"], "effective_scenario.json")))
    mat = scen["materials"][0]
    e_star = mat["young"] / (1 - mat["poisson"] ** 2)
    r = run["summary"]["diameter_m"] / 2
    fmax = max(num(p, "platen_force_N") for p in run["ld"])
    forces = [fmax * k / n for k in range(n + 1)]
    return [2 * (9 * f * f / (16 * r * e_star ** 2)) ** (1 / 3) for f in forces], forces


def loaded_curve(run):
    """Platen displacement (µm) and force (N) of load_displacement.csv, without the samples after the split."""
    u = [1e6 * num(p, "platen_displacement_m") for p in run["ld"]]
    f = [num(p, "platen_force_N") for p in run["ld"]]
    while len(f) > 1 and f[-1] <= 0 < max(f):
        u.pop()
        f.pop()
    return u, f


def plot_curves(plt, runs, path):
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.6))
    colours = {"bullet": "#2ca02c", "ode": "#9467bd", "lsdem": "#ff7f0e"}
    for eng in ENGINES:
        # Up to the stress model's split the two models' runs are the same run (checked in
        # check_models_agree): one curve per engine, the peridynamics run (it goes further).
        run = runs.get((eng, "peridynamics", BUILDERS[0]))
        if not run:
            continue
        u, f = loaded_curve(run)
        thin = eng == "lsdem"
        ax.plot(u, f, color=colours[eng], lw=0.5 if thin else 1.5, alpha=0.6 if thin else 1, label=eng)
        ax.plot(u[-1], f[-1], "o", color=colours[eng], mec="black", ms=6)
        st = runs.get((eng, "stress", BUILDERS[0]))
        if st:
            us, fs = loaded_curve(st)
            ax.plot(us[-1], fs[-1], "X", color=colours[eng], mec="black", ms=8)
    ax.plot([], [], "o", color="white", mec="black", label="last loaded sample (peridynamics split)")
    ax.plot([], [], "X", color="white", mec="black", ms=8, label="last loaded sample (stress-model split)")
    ref = runs.get(("bullet", "peridynamics", BUILDERS[0]))
    if ref:
        hu, hf = hertz_curve(ref)
        ax.plot([1e6 * v for v in hu], hf, ":", color="black", lw=1.2, label="Hertz, E = 100 GPa, ν = 0.15 (reference)")
    ax.set_xlabel("platen displacement (µm)")
    ax.set_ylabel("platen force (N)")
    ax.set_title("(a) platen force against displacement, up to the split", fontsize=10)
    ax.legend(fontsize=7, loc="lower right")
    ax.grid(alpha=0.3)

    run = runs.get(("lsdem", "stress", BUILDERS[0]))
    if run:
        area = platen_area(run["series"])
        e = split_event(run)
        t_split = num(e, "time_s")
        rows = [r for r in run["series"] if num(r, "time_s") >= t_split - 5e-4]
        t = [1e3 * num(r, "time_s") for r in rows]
        bx.plot(t, [num(r, "platen_force_N") for r in rows], color="#ff7f0e", lw=0.8, label="platen force (sampled every 10 steps)")
        bx.plot(t, [num(r, "floor_force_N") for r in rows], color="#8c564b", lw=0.8, alpha=0.7, label="floor force")
        bx.plot(t, [num(r, "target_stress_Pa") * area for r in rows], color="black", lw=1, label="commanded force")
        checks = [ev for ev in run["events"] if num(ev, "time_s") >= t_split - 5e-4]
        bx.plot([1e3 * num(ev, "time_s") for ev in checks], [num(ev, "max_force_N") for ev in checks], "s", ms=3,
                color="#d62728", label="largest contact force at a breakage check")
        bx.axvline(1e3 * t_split, color="#d62728", lw=0.8, ls=":")
        bx.text(1e3 * t_split, bx.get_ylim()[1], " split", color="#d62728", fontsize=8, va="top")
        bx.set_xlabel("time (ms)")
        bx.set_ylabel("force (N)")
        bx.set_title("(b) lsdem + stress: the last 0.5 ms before the split", fontsize=10)
        bx.legend(fontsize=7, loc="lower left")
        bx.grid(alpha=0.3)
    fig.tight_layout()
    save(fig, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", help="the crumble compare output folder")
    ap.add_argument("--every-step", help="the compare of the stress model checked every step (engine.type varied)")
    ap.add_argument("--also", action="append", default=[],
                    help="another compare of the stress model with engine.type varied: its rows are printed too")
    ap.add_argument("--img-dir", default="docs/img")
    a = ap.parse_args()
    runs = load_compare(a.out)
    if not runs:
        sys.exit("plot-methods-compared: no run finished in " + a.out)
    every = load_by_engine(a.every_step) if a.every_step else {}
    check_same_runs(runs)
    any_run = next(iter(runs.values()))
    d = any_run["summary"]["diameter_m"]
    stress_run = next((r for k, r in runs.items() if k[1] == "stress"), None)
    strength = num(split_event(stress_run), "strength_Pa") if stress_run else 35e6
    print_tables(runs, every, strength, d)
    for extra in a.also:
        print_by_engine(extra, load_by_engine(extra))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("plot-methods-compared: matplotlib is not importable; no figure drawn", file=sys.stderr)
        sys.exit(3)
    os.makedirs(a.img_dir, exist_ok=True)
    plot_force(plt, runs, every, strength, d, os.path.join(a.img_dir, "methods-compared-single-grain-force.png"))
    plot_curves(plt, runs, os.path.join(a.img_dir, "methods-compared-single-grain-curves.png"))


if __name__ == "__main__":
    main()
