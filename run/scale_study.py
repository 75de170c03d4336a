"""run/scale_study's last step: gathers the measured memory runs and the
modelled cases into DIR/scale_study.json, projects the efficiencies and
draws DIR/scale_study.png (efficiency against ranks, strong and weak; halo
bytes per rank against ranks). Prints both tables."""
import json
import math
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

out = sys.argv[1]
study = {"machine": "this machine (see docs/performance.md)"}


def memory_runs():
    runs = []
    path = os.path.join(out, "memory", "runs.txt")
    if not os.path.exists(path):
        return runs
    for line in open(path):
        ranks, size, rc, d = line.split()
        ranks, size, rc = int(ranks), int(size), int(rc)
        rss = []
        for r in range(ranks):
            f = os.path.join(d, "rss.%d" % r)
            if os.path.exists(f):  # /usr/bin/time's last line: max RSS in KiB
                rss.append(1024 * int(open(f).read().split()[-1]))
        run = {"ranks": ranks, "size": size, "exit_code": rc}
        err = open(os.path.join(d, "stderr")).read()
        if rc != 0:
            run["refused"] = err.strip().splitlines()[-1] if err.strip() else "exit %d" % rc
        if rss and rc == 0:
            run["peak_rss_bytes_max"] = max(rss)
            run["peak_rss_bytes_mean"] = sum(rss) / len(rss)
            run["peak_rss_bytes_per_rank"] = rss
        rep = os.path.join(d, "out", "report.json")
        if os.path.exists(rep):
            run["report_peak_rss_bytes"] = json.load(open(rep))["peak_rss_bytes"]
        runs.append(run)
    return runs


study["memory_measured"] = memory_runs()
avail = os.path.join(out, "memory", "available.txt")
if os.path.exists(avail):
    study["memory_available_before_8_ranks"] = open(avail).read().strip()

model_path = os.path.join(out, "scale_model.json")
model = json.load(open(model_path)) if os.path.exists(model_path) else None
study["model"] = model


def seconds(model, size, parts):
    for c in model["cases"]:
        if c["size"] == size and c["parts"] == parts and "iteration_seconds_modelled" in c:
            return c["iteration_seconds_modelled"]
    return None


# Bytes a particle today, from the one-rank run; a rank that held only its
# tiles and ghosts would need about that many for each (an upper bound: the
# largest owned count and the largest ghost count may be on different ranks).
one = [r for r in study["memory_measured"] if r["ranks"] == 1 and "peak_rss_bytes_max" in r]
per_particle = one[0]["peak_rss_bytes_max"] / one[0]["size"] ** 2 if one else 2400.0
study["bytes_per_particle_measured_1_rank"] = per_particle
def efficiencies(model):
    """Strong (1000^2 and 4000^2 on 1..1024 ranks) and weak (250k particles a
    rank: 500^2 on 1, 1000^2 on 4, ... 16000^2 on 1024) from the modelled
    iteration times."""
    strong = {}
    for size in (1000, 4000):
        t1 = seconds(model, size, 1)
        rows = []
        for c in model["cases"]:
            if c["size"] == size and t1 and "iteration_seconds_modelled" in c:
                p = c["parts"]
                rows.append({"ranks": p, "seconds": c["iteration_seconds_modelled"],
                             "efficiency": t1 / (p * c["iteration_seconds_modelled"])})
        strong[str(size)] = rows
    weak = []
    t1 = seconds(model, 500, 1)
    for p in (1, 4, 16, 64, 256, 1024):
        size = int(round(500 * math.sqrt(p)))
        t = seconds(model, size, p)
        if t1 and t:
            weak.append({"ranks": p, "size": size, "seconds": t, "efficiency": t1 / t})
    return strong, weak


if model:
    for c in model["cases"]:
        c["rank_memory_if_local_bytes_modelled"] = per_particle * (c["owned_particles"]["max"] + c["ghost_particles"]["max"])
    study["strong_modelled"], study["weak_modelled"] = efficiencies(model)
cluster_path = os.path.join(out, "scale_model_cluster.json")
cluster = json.load(open(cluster_path)) if os.path.exists(cluster_path) else None
if cluster:
    strong, weak = efficiencies(cluster)
    study["cluster_network_assumed"] = {"alpha_seconds": cluster["alpha_seconds"],
                                        "beta_bytes_per_second": cluster["beta_bytes_per_second"],
                                        "strong_modelled": strong, "weak_modelled": weak}

json.dump(study, open(os.path.join(out, "scale_study.json"), "w"), indent=1)

print("measured: peak RSS per rank, 1 thread a rank, finest mesh")
print("| ranks | cloth | peak RSS max [GB] | mean [GB] | report.json [GB] |")
print("|---|---|---|---|---|")
for r in study["memory_measured"]:
    if "peak_rss_bytes_max" in r:
        print("| %d | %d x %d | %.2f | %.2f | %.2f |" % (r["ranks"], r["size"], r["size"], 1e-9 * r["peak_rss_bytes_max"],
              1e-9 * r["peak_rss_bytes_mean"], 1e-9 * r.get("report_peak_rss_bytes", 0)))
    else:
        print("| %d | %d x %d | refused: %s | | |" % (r["ranks"], r["size"], r["size"], r.get("refused", "?")))
if model:
    if "ping_pong" in model:
        pp = model["ping_pong"]
        print("measured: alpha %.3g s, beta %.3g GB/s; product %.3g s, vectors %.3g s per particle and CG iteration" % (
            pp["alpha_seconds"], 1e-9 * pp["beta_bytes_per_second"], model["product_seconds_per_particle"],
            model["vector_seconds_per_particle"]))
    print("modelled: per case (max over ranks / mean)")
    print("| cloth | ranks | imbalance | edge cut | ghosts max/mean | halo kB/CG it. max/mean | neighbours max/mean | fold band: method, tiles, MB | it. [ms] | rank memory if local [MB] |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for c in model["cases"]:
        m = c["fold_band_migration"]
        print("| %d | %d | %.3f | %d | %.0f / %.0f | %.1f / %.1f | %.0f / %.1f | %s, %d, %.1f | %s | %.0f |" % (
            c["size"], c["parts"], c["imbalance"], c["edge_cut"], c["ghost_particles"]["max"],
            c["ghost_particles"]["mean"], 1e-3 * c["halo_bytes_cg_iteration"]["max"],
            1e-3 * c["halo_bytes_cg_iteration"]["mean"], c["neighbours"]["max"], c["neighbours"]["mean"],
            m["method"], m["tiles_moved"], 1e-6 * m["bytes"],
            "%.3f" % (1e3 * c["iteration_seconds_modelled"]) if "iteration_seconds_modelled" in c else "-",
            1e-6 * c["rank_memory_if_local_bytes_modelled"]))
    for size, rows in study.get("strong_modelled", {}).items():
        print("modelled strong scaling %s^2: " % size + ", ".join("%d: %.2f" % (r["ranks"], r["efficiency"]) for r in rows))
    print("modelled weak scaling (250k particles a rank): " +
          ", ".join("%d: %.2f" % (r["ranks"], r["efficiency"]) for r in study.get("weak_modelled", [])))
    cl = study.get("cluster_network_assumed")
    if cl:
        for size, rows in cl["strong_modelled"].items():
            print("assumed network (2 us, 10 GB/s), strong %s^2: " % size +
                  ", ".join("%d: %.2f" % (r["ranks"], r["efficiency"]) for r in rows))
        print("assumed network (2 us, 10 GB/s), weak: " +
              ", ".join("%d: %.2f" % (r["ranks"], r["efficiency"]) for r in cl["weak_modelled"]))

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    colour = {"1000": "C0", "4000": "C1", "weak": "C2"}  # one per series, solid here, dashed assumed
    for size, rows in study.get("strong_modelled", {}).items():
        ax1.plot([r["ranks"] for r in rows], [r["efficiency"] for r in rows], "o-", color=colour[size],
                 label="strong, %s^2" % size)
    w = study.get("weak_modelled", [])
    ax1.plot([r["ranks"] for r in w], [r["efficiency"] for r in w], "s-", color=colour["weak"],
             label="weak, 250k a rank")
    if cl:
        for size, rows in cl["strong_modelled"].items():
            ax1.plot([r["ranks"] for r in rows], [r["efficiency"] for r in rows], "o--", color=colour[size],
                     alpha=0.6, label="strong, %s^2, 2 us network (assumed)" % size)
        w = cl["weak_modelled"]
        ax1.plot([r["ranks"] for r in w], [r["efficiency"] for r in w], "s--", color=colour["weak"], alpha=0.6,
                 label="weak, 2 us network (assumed)")
    ax1.set_xscale("log", base=2)
    ax1.set_xlabel("ranks")
    ax1.set_ylabel("efficiency (modelled)")
    ax1.set_ylim(0, 1.05)
    for size in sorted({c["size"] for c in model["cases"]}):
        cs = [c for c in model["cases"] if c["size"] == size and c["parts"] > 1]
        ax2.plot([c["parts"] for c in cs], [c["halo_bytes_cg_iteration"]["max"] for c in cs], "o-", label="%d^2 max" % size)
    ax2.set_xscale("log", base=2)
    ax2.set_yscale("log")
    ax2.set_xlabel("ranks")
    ax2.set_ylabel("halo bytes per rank per CG iteration")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("Scale model: METIS tiles of %d, alpha-beta from a ping-pong here" % model["tile"])
    fig.tight_layout()
    fig.savefig(os.path.join(out, "scale_study.png"), dpi=100)
    print("wrote %s" % os.path.join(out, "scale_study.png"))
print("wrote %s" % os.path.join(out, "scale_study.json"))
