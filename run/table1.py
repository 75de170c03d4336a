"""Table 1 from run/table1's runs: reads each run's report.json and the final
frame of its drape.h5, prints the table and writes table1.json."""
import json
import sys
import tomllib

import h5py
import numpy as np


def final_positions(run):
    with h5py.File(f"{run}/drape.h5", "r") as f:
        last = sorted(f["frames"].keys())[-1]
        return np.array(f["frames"][last]["positions"])  # (NI, NJ, 3)


def cloth_width(run):
    """The cloth's size along i, from the scene the run wrote (a restarted
    run's first frame is not the flat cloth)."""
    with h5py.File(f"{run}/drape.h5", "r") as f:
        scene = tomllib.loads(f.attrs["scene_toml"].decode())
        return float(scene["cloth"]["size"][0])


def on_grid(x, n):
    """Samples the surface x (m x m x 3) at the n x n grid's parameters (bilinear)."""
    m = x.shape[0]
    u = np.linspace(0, m - 1, n)
    i0 = np.minimum(np.floor(u).astype(int), m - 2)
    t = u - i0
    rows = (1 - t)[:, None, None] * x[i0] + t[:, None, None] * x[i0 + 1]
    cols = (1 - t)[None, :, None] * rows[:, i0] + t[None, :, None] * rows[:, i0 + 1]
    return cols


def main():
    out, pairs = sys.argv[1], sys.argv[2:]
    rows = []
    for pair in pairs:
        fine, coarse = (int(v) for v in pair.split(":"))
        runs = [("finest", f"{out}/{fine}-finest", fine), ("AMRC", f"{out}/{fine}-amrc", fine),
                ("coarsest", f"{out}/{coarse}-coarsest", coarse)]
        reports = {name: json.load(open(f"{path}/report.json")) for name, path, _ in runs}
        ref_x = final_positions(runs[0][1])
        ref_cost = reports["finest"]["final_cost"]["total"]
        width = cloth_width(runs[0][1])
        for name, path, n in runs:
            r = reports[name]
            x = on_grid(final_positions(path), fine)
            rms = float(np.sqrt(np.mean(np.sum((x - ref_x) ** 2, axis=2)))) / width
            pa = r["particles_active"]
            rows.append({
                "size": fine, "mesh": name, "grid": r["grid"], "wall_seconds": r["wall_seconds"],
                "particles_min": pa["min"], "particles_max": pa["max"],
                # active particles per CG iteration (reports before it existed: the final count)
                "particles_mean": pa.get("mean", pa["final"]), "iterations": r["iterations"],
                "quality_error_cost": (r["final_cost"]["total"] - ref_cost) / ref_cost if ref_cost else 0.0,
                "quality_error_geometric": rms, "max_penetration": r["max_penetration"],
                "simulated_seconds": r["simulated_seconds"], "steps": r["steps"], "at_rest": r["at_rest"],
                # kinks at the mesh spacing in the final state (reports before it existed: none)
                "zigzag_share": r.get("zigzag", {}).get("share"),
            })
    json.dump({"rows": rows}, open(f"{out}/table1.json", "w"), indent=1)
    print("%-5s %-9s %10s %8s %8s %15s %8s %12s %12s %12s %7s" % (
        "size", "mesh", "grid", "wall [s]", "t [s]", "particles", "mean", "cost err", "geom err", "penetr. [m]",
        "zigzag"))
    for r in rows:
        parts = str(r["particles_min"]) if r["particles_min"] == r["particles_max"] else \
            "%d-%d" % (r["particles_min"], r["particles_max"])
        zz = "-" if r["zigzag_share"] is None else "%.3f" % r["zigzag_share"]
        print("%-5d %-9s %10s %8.1f %8.3f%s %15s %8.0f %+12.3f %12.4f %12.2g %7s" % (
            r["size"], r["mesh"], "%dx%d" % tuple(r["grid"]), r["wall_seconds"], r["simulated_seconds"],
            "*" if r["at_rest"] else " ", parts, r["particles_mean"],
            r["quality_error_cost"], r["quality_error_geometric"], r["max_penetration"], zz))
    print("(t: simulated seconds, * at rest; mean: active particles per CG iteration; zigzag: share of\n"
          " neighbouring turns on the mesh lines that kink at the mesh spacing, report.json zigzag)")
    for size in sorted({r["size"] for r in rows}):
        f, a, c = (next(r for r in rows if r["size"] == size and r["mesh"] == m)
                   for m in ("finest", "AMRC", "coarsest"))
        work = lambda r: r["particles_mean"] * r["iterations"]  # what a CG iteration's cost scales with
        print("%d: AMRC %.2fx faster than the finest mesh (%.2fx less work in particle-iterations); geometric "
              "error %.4f vs the coarsest's %.4f (%.2f of it)"
              % (size, f["wall_seconds"] / a["wall_seconds"], work(f) / max(work(a), 1e-300),
                 a["quality_error_geometric"], c["quality_error_geometric"],
                 a["quality_error_geometric"] / max(c["quality_error_geometric"], 1e-300)))


main()
