"""Tables of run/scaling's rank parts from bench/ranks_threads' JSON lines, one
run a line: "layouts" (ranks x threads = cores: time against the first layout,
1 x N), "strong" (the same cloth on 1, 2, 4, ... ranks: speed-up and
efficiency against one rank) and "weak" (a rank's share of the cloth fixed:
one rank's time over P ranks'); the halo and reduction shares, and whether the
checksums agree where the cloth is the same."""
import json
import sys

part, lines, out = sys.argv[1], sys.argv[2], sys.argv[3]
rows = [json.loads(l) for l in open(lines) if l.strip()]
json.dump({"part": part, "rows": rows}, open(out, "w"), indent=1)
base = rows[0]
print("%-9s %-9s %-7s %9s %9s %11s %7s %9s  %s" % (
    "layout", "particles", "solver", "time [s]", "vs first", "efficiency", "halo %", "reduce %", "checksum"))
for r in rows:
    for k in ("cg", "newton"):
        d, t1 = r[k], base[k]["seconds"]
        cores = r["ranks"] * r["threads"] / (base["ranks"] * base["threads"])
        # strong: t1 / (P t); weak (work grows with P): t1 / t; layouts: the same cores
        eff = t1 / d["seconds"] / (cores if part == "strong" else 1)
        print("%-9s %-9d %-7s %9.2f %9.2f %11.2f %7.1f %9.1f  %s" % (
            "%dx%d" % (r["ranks"], r["threads"]), r["particles"], k, d["seconds"], d["seconds"] / t1, eff,
            100 * d["halo_seconds"] / d["seconds"], 100 * d["reduction_seconds"] / d["seconds"], d["checksum"][:16]))
if part != "weak":
    sums = {(k, r[k]["checksum"]) for r in rows for k in ("cg", "newton")}
    print("checksums agree" if len(sums) == 2 else "CHECKSUMS DIFFER")
