"""Table 1 from run/table1's runs: reads each run's report.json and the final
frame of its drape.h5, prints the table and writes table1.json, and
table1-SIZE.png: where AMRC's and the coarsest mesh's drapes lie off the
finest one's, beside AMRC's final leaf levels.
Usage: table1.py DIR PAIR... [--ledger LEDGER.tsv]
With --ledger (run/table1 writes DIR/ledger.tsv; docs/data/table1-257-ledger.tsv
is the one behind docs/validation.md's Table 1 at 257:65), a row that ran in
segments, on different machines or thread counts, gets its time from the
ledger: see campaign_time.
run/table1 also calls it as
  table1.py --state RUN_DIR     prints new, stopped or done (see row_state)
  table1.py --ledger-line LEDGER RUN_DIR START BINARY
                                appends the segment that just ended (ledger_line)"""
import collections
import json
import os
import socket
import sys
import time
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


def point_segment(p, a, b):
    ab = b - a
    t = np.clip(np.sum((p - a) * ab, axis=-1) / np.maximum(np.sum(ab * ab, axis=-1), 1e-300), 0, 1)
    return np.linalg.norm(p - a - t[..., None] * ab, axis=-1)


def point_triangle(p, a, b, c):
    """Distance from points p to triangles abc (broadcast over leading axes)."""
    ab, ac, ap = b - a, c - a, p - a
    d00, d01, d11 = (np.sum(u * v, axis=-1) for u, v in ((ab, ab), (ab, ac), (ac, ac)))
    d20, d21 = np.sum(ap * ab, axis=-1), np.sum(ap * ac, axis=-1)
    den = np.maximum(d00 * d11 - d01 * d01, 1e-300)
    v, w = (d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den
    n = np.cross(ab, ac)
    plane = np.abs(np.sum(ap * n, axis=-1)) / np.maximum(np.linalg.norm(n, axis=-1), 1e-300)
    edges = np.minimum(np.minimum(point_segment(p, a, b), point_segment(p, b, c)), point_segment(p, c, a))
    return np.where((v >= 0) & (w >= 0) & (v + w <= 1), plane, edges)


def surface_distance(x, ref, k=6):
    """Each point of x (n x n x 3) to the surface of ref (m x m x 3, each quad
    two triangles): the nearest of the triangles round ref's k vertices
    nearest the point. Unlike the distance between the same material points,
    it does not count cloth that slid along its own surface."""
    from scipy.spatial import cKDTree
    m = ref.shape[0]
    q = x.reshape(-1, 3)
    _, idx = cKDTree(ref.reshape(-1, 3)).query(q, k=k)
    vi, vj = idx // m, idx % m
    best = np.full(len(q), np.inf)
    for di in (-1, 0):
        for dj in (-1, 0):
            i, j = np.clip(vi + di, 0, m - 2), np.clip(vj + dj, 0, m - 2)
            p00, p10, p01, p11 = ref[i, j], ref[i + 1, j], ref[i, j + 1], ref[i + 1, j + 1]
            for a, b, c in ((p00, p10, p11), (p00, p11, p01)):
                best = np.minimum(best, point_triangle(q[:, None, :], a, b, c).min(axis=1))
    return best.reshape(x.shape[:2])


def final_field(run, name):
    with h5py.File(f"{run}/drape.h5", "r") as f:
        last = sorted(f["frames"].keys())[-1]
        return np.array(f["frames"][last][name])


def plot_errors(out, fine, runs, ref_x, width):
    """table1-FINE.png: the distance of each point of AMRC's and the coarsest
    mesh's drapes from the same point of the finest one's (over the cloth's
    parameters, per width), beside AMRC's final leaf levels."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    dist = {name: np.linalg.norm(on_grid(final_positions(path), fine) - ref_x, axis=2) / width
            for name, path, _ in runs if name != "finest"}
    top = max(float(d.max()) for d in dist.values()) or 1.0
    fig, ax = plt.subplots(1, 3, figsize=(13, 4.2), constrained_layout=True)
    level = final_field(dict((n, p) for n, p, _ in runs)["AMRC"], "level")
    im = ax[0].imshow(level.T, origin="lower", cmap="viridis", interpolation="nearest")
    fig.colorbar(im, ax=ax[0], ticks=range(int(level.max()) + 1), label="leaf level (0: finest)")
    ax[0].set_title("AMRC: final leaf levels")
    for a, name in zip(ax[1:], ("AMRC", "coarsest")):
        d = dist[name]
        im = a.imshow(d.T, origin="lower", cmap="magma", vmin=0, vmax=top, interpolation="nearest")
        a.set_title("%s: distance from the finest drape\n(RMS %.4f of the width)"
                    % (name, float(np.sqrt(np.mean(d ** 2)))))
    fig.colorbar(im, ax=list(ax[1:]), label="distance / cloth width")
    for a in ax:
        a.set_xlabel("i")
        a.set_ylabel("j")
    path = f"{out}/table1-{fine}.png"
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


LEDGER_HEAD = ("row", "segment", "wall_seconds", "steps", "simulated_seconds", "at_rest", "particles_mean",
               "iterations", "date", "host", "started", "threads", "cpu_seconds", "particles_min",
               "particles_max", "binary")


def row_state(run):
    """Where a row's folder stands: "done" (a report of a run that ended by
    itself), "stopped" (a checkpoint to continue from: the run was stopped by a
    signal or its wall limit, or killed before it wrote a report) or "new"."""
    checkpoint = os.path.isfile(os.path.join(run, "checkpoint.h5"))
    try:
        r = json.load(open(os.path.join(run, "report.json")))
    except (OSError, ValueError):
        return "stopped" if checkpoint else "new"
    if r.get("stopped_by_signal") or r.get("stopped_by_wall_limit"):
        return "stopped" if checkpoint else "new"
    return "done"


def ledger_line(run, start, binary):
    """One ledger line for a segment that just ended in `run`: row, segment,
    its wall time, the cumulative steps, simulated time, at rest, mean active
    particles and CG iterations, date, host, start (epoch), threads, its CPU
    time (all threads), its fewest and most active particles, and the first 12
    digits of the binary's sha256 (segments of different code are timed apart).
    A segment without a report (killed outright) gets NA, and the reason."""
    seg = os.path.basename(os.path.normpath(run))
    row = seg.split(".")[0]
    now, host = time.strftime("%F %T"), socket.gethostname()
    try:
        r = json.load(open(os.path.join(run, "report.json")))
    except (OSError, ValueError) as e:
        return "\t".join([row, seg] + ["NA"] * 6 + [now, host, str(start), "NA", "# no report: %s" % e])
    pa = r.get("particles_active", {})
    return "\t".join(str(v) for v in (
        row, seg, r["wall_seconds"], r["steps"], r["simulated_seconds"], r["at_rest"], pa.get("mean", "NA"),
        r["iterations"], now, host, start, r["threads"], r.get("cpu_seconds", "NA"), pa.get("min", "NA"),
        pa.get("max", "NA"), binary))


def ledger_row(run):
    """The campaign row a run folder belongs to: its real name up to the segment
    number (257-amrc-lo.3 and a link 257-amrc to it: 257-amrc-lo)."""
    return os.path.basename(os.path.realpath(run)).split(".")[0]


def ledger_segments(path):
    """A campaign ledger's segments per row, in order (lines without a report skipped)."""
    rows = collections.defaultdict(list)
    try:
        f = open(path)
    except OSError as e:
        sys.exit(f"table1.py: cannot read the ledger {path}: {e.strerror}")
    with f:
        head = f.readline().rstrip("\n").split("\t")
        for n, line in enumerate(f, start=2):
            v = dict(zip(head, line.rstrip("\n").split("\t")))
            if v.get("wall_seconds", "NA") == "NA":
                continue
            try:
                rows[v["row"]].append({
                    "wall": float(v["wall_seconds"]),
                    "cpu": float(v["cpu_seconds"]) if v.get("cpu_seconds", "NA") != "NA" else None,
                    "iterations": int(v["iterations"]), "mean": float(v["particles_mean"]),
                    "min": int(v["particles_min"]) if v.get("particles_min", "NA") != "NA" else None,
                    "max": int(v["particles_max"]) if v.get("particles_max", "NA") != "NA" else None,
                    # segments of different code are timed apart (binary NA: before the ledger had it)
                    "machine": (v["host"], int(v["threads"]) if v.get("threads") else 1,
                                v.get("binary") or "NA")})
            except (KeyError, ValueError) as e:
                sys.exit(f"table1.py: {path}:{n}: unreadable ledger line ({e})")
    return rows


def campaign_time(segments, machine):
    """A row's time on one machine (host, threads, binary), from its segments. Each
    segment did mean * iterations - (the same before it) particle-iterations
    (the ledger's counts are cumulative). The segments that ran on `machine`
    give the row's seconds per particle-iteration there; the others' work is
    counted at that rate. With every segment on `machine` this is the plain
    sum of the wall times. Returns wall and CPU seconds (CPU None unless every
    segment on `machine` has it) and the particle-iterations."""
    done, on, wall, cpu, work_on, work_off = 0.0, [], 0.0, 0.0, 0.0, 0.0
    for seg in segments:
        total = seg["mean"] * seg["iterations"]
        work = total - done
        done = total
        if seg["machine"] == machine:
            on.append(seg)
            wall += seg["wall"]
            cpu = None if cpu is None or seg["cpu"] is None else cpu + seg["cpu"]
            work_on += work
        else:
            work_off += work
    if not on or (work_on <= 0 and work_off > 0):
        return None
    scale = 1 + work_off / work_on if work_off > 0 else 1.0
    return {"wall_seconds": wall * scale, "cpu_seconds": None if cpu is None else cpu * scale,
            "particle_iterations": done, "measured_share": work_on / done if done > 0 else 1.0,
            "segments": len(segments)}


def reference_machine(segments):
    """The (host, threads, binary) on which the row spent the most wall time."""
    spent = collections.Counter()
    for seg in segments:
        spent[seg["machine"]] += seg["wall"]
    return spent.most_common(1)[0][0]


def table_row(fine, name, path, r, ref_x, ref_cost, width):
    """One row of the table: the run in `path` (report r) against the finest
    drape ref_x (its final positions) and cost ref_cost."""
    x = on_grid(final_positions(path), fine)
    rms = float(np.sqrt(np.mean(np.sum((x - ref_x) ** 2, axis=2)))) / width
    surface = float(np.sqrt(np.mean(surface_distance(x, ref_x) ** 2))) / width
    pa = r["particles_active"]
    return {
        "size": fine, "mesh": name, "ledger_row": ledger_row(path), "grid": r["grid"],
        "wall_seconds": r["wall_seconds"],
        "particles_min": pa["min"], "particles_max": pa["max"],
        # active particles per CG iteration (reports before it existed: the final count)
        "particles_mean": pa["mean"] if "mean" in pa else pa["final"], "iterations": r["iterations"],
        "quality_error_cost": (r["final_cost"]["total"] - ref_cost) / ref_cost if ref_cost else 0.0,
        # the same material points' distance, and the distance to the finest surface
        "quality_error_geometric": rms, "quality_error_surface": surface,
        "max_penetration": r["max_penetration"],
        "simulated_seconds": r["simulated_seconds"], "steps": r["steps"], "at_rest": r["at_rest"],
        # steps accepted at the iteration limit: a row's drape is only as good as
        # its steps converged (counted over restarts; reports before it existed: None)
        "unconverged_steps": r.get("unconverged_steps"),
        # kinks at the mesh spacing in the final state (reports before it existed: none)
        "zigzag_share": r.get("zigzag", {}).get("share"),
    }


def main():
    args = sys.argv[1:]
    if args[:1] == ["--state"] and len(args) == 2:
        print(row_state(args[1]))
        return
    if args[:1] == ["--ledger-line"] and len(args) == 5:
        path, run, start, binary = args[1:]
        new = not os.path.exists(path)
        with open(path, "a") as f:
            f.write(("\t".join(LEDGER_HEAD) + "\n" if new else "") + ledger_line(run, start, binary) + "\n")
        return
    ledger = None
    if "--ledger" in args:
        k = args.index("--ledger")
        if k + 1 >= len(args):
            sys.exit("table1.py: --ledger needs a file")
        ledger = ledger_segments(args[k + 1])
        del args[k:k + 2]
    out, pairs = args[0], args[1:]
    rows, pictures = [], []
    for pair in pairs:
        fine, coarse = (int(v) for v in pair.split(":"))
        runs = [("finest", f"{out}/{fine}-finest", fine), ("AMRC", f"{out}/{fine}-amrc", fine),
                ("coarsest", f"{out}/{coarse}-coarsest", coarse)]
        reports = {name: json.load(open(f"{path}/report.json")) for name, path, _ in runs}
        ref_x = final_positions(runs[0][1])
        ref_cost = reports["finest"]["final_cost"]["total"]
        width = cloth_width(runs[0][1])
        pictures.append((fine, runs, ref_x, width))
        for name, path, _ in runs:
            rows.append(table_row(fine, name, path, reports[name], ref_x, ref_cost, width))
    if ledger is not None:
        apply_ledger(rows, ledger)
    json.dump({"rows": rows}, open(f"{out}/table1.json", "w"), indent=1)
    print("%-5s %-9s %10s %8s %8s %15s %8s %10s %9s %9s %11s %7s %7s" % (
        "size", "mesh", "grid", "wall [s]", "t [s]", "particles", "mean", "cost err", "geom err", "surf err",
        "penetr. [m]", "zigzag", "unconv"))
    for r in rows:
        parts = str(r["particles_min"]) if r["particles_min"] == r["particles_max"] else \
            "%d-%d" % (r["particles_min"], r["particles_max"])
        zz = "-" if r["zigzag_share"] is None else "%.3f" % r["zigzag_share"]
        wall = "-" if r["wall_seconds"] is None else "%.1f" % r["wall_seconds"]
        unconv = "-" if r["unconverged_steps"] is None else str(r["unconverged_steps"])
        print("%-5d %-9s %10s %8s %8.3f%s %15s %8.0f %+10.3f %9.4f %9.4f %11.2g %7s %7s" % (
            r["size"], r["mesh"], "%dx%d" % tuple(r["grid"]), wall, r["simulated_seconds"],
            "*" if r["at_rest"] else " ", parts, r["particles_mean"], r["quality_error_cost"],
            r["quality_error_geometric"], r["quality_error_surface"], r["max_penetration"], zz, unconv))
    print("(t: simulated seconds, * at rest; mean: active particles per CG iteration; geom err: RMS\n"
          " distance from the same material point of the finest drape, surf err: from the finest drape's\n"
          " surface, both per cloth width; zigzag: share of neighbouring turns on the mesh lines that kink\n"
          " at the mesh spacing, report.json zigzag; unconv: steps accepted unconverged)")
    for size in sorted({r["size"] for r in rows}):
        f, a, c = (next(r for r in rows if r["size"] == size and r["mesh"] == m)
                   for m in ("finest", "AMRC", "coarsest"))
        work = lambda r: r["particles_mean"] * r["iterations"]  # what a CG iteration's cost scales with
        speed = "not timed" if f["wall_seconds"] is None or a["wall_seconds"] is None else \
            "%.2fx faster" % (f["wall_seconds"] / a["wall_seconds"])
        print("%d: AMRC %s than the finest mesh (%.2fx less work in particle-iterations); geometric "
              "error %.4f vs the coarsest's %.4f (%.2f of it)"
              % (size, speed, work(f) / max(work(a), 1e-300),
                 a["quality_error_geometric"], c["quality_error_geometric"],
                 a["quality_error_geometric"] / max(c["quality_error_geometric"], 1e-300)))
        print("%d: surface error %.4f vs the coarsest's %.4f (%.2f of it)"
              % (size, a["quality_error_surface"], c["quality_error_surface"],
                 a["quality_error_surface"] / max(c["quality_error_surface"], 1e-300)))
        if f.get("cpu_seconds") and a.get("cpu_seconds"):
            print("%d: in CPU time AMRC is %.2fx faster" % (size, f["cpu_seconds"] / a["cpu_seconds"]))
    for fine, runs, ref_x, width in pictures:  # last: a picture that fails costs no table
        try:
            path = plot_errors(out, fine, runs, ref_x, width)
        except Exception as e:  # noqa: BLE001 (any plotting failure)
            print("table1.py: no picture for %d: %s" % (fine, e), file=sys.stderr)
            continue
        if path:
            print("picture:", path)


def apply_ledger(rows, ledger):
    """Times from the campaign's ledger, on the machine the AMRC row ran on."""
    for size in sorted({r["size"] for r in rows}):
        amrc = ledger.get(next(r["ledger_row"] for r in rows if r["size"] == size and r["mesh"] == "AMRC"))
        if not amrc:
            continue
        machine = reference_machine(amrc)
        for r in rows:
            segs = ledger.get(r["ledger_row"])
            if r["size"] != size or not segs:
                continue  # not in the ledger: its own report's time
            t = campaign_time(segs, machine)
            if t is None and len(segs) == 1:
                continue  # one whole segment elsewhere (SIDE_BY_SIDE's coarsest row): its own report's time
            if t is None:  # a rate from other code or another machine would mislead
                r.update(wall_seconds=None, cpu_seconds=None, untimed=True)
                print("table1.py: %d %s: no segment of %s ran on %s, %d thread(s), binary %s: not timed"
                      % (size, r["mesh"], r["ledger_row"], *machine), file=sys.stderr)
                continue
            r.update(t)
            lo = [g["min"] for g in segs if g["min"] is not None]
            hi = [g["max"] for g in segs if g["max"] is not None]
            if lo and hi:  # a segment's report counts its own steps only
                r["particles_min"], r["particles_max"] = min(lo), max(hi)
            r["machine"] = "%s, %d thread(s), binary %s" % machine
    for r in rows:
        if "machine" in r:
            print("%d %s: %.0f s on %s over %d segment(s), %.0f%% of its work timed there%s"
                  % (r["size"], r["mesh"], r["wall_seconds"], r["machine"], r["segments"],
                     100 * r["measured_share"],
                     "" if r["cpu_seconds"] is None else "; CPU %.0f s" % r["cpu_seconds"]))


if __name__ == "__main__":
    main()
