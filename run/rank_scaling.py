"""Tables of run/scaling's strong and weak parts from bench/ranks_threads' JSON
lines: time, speed-up and efficiency against one rank, the halo and reduction
shares, and whether the checksums agree where the cloth is the same."""
import json
import sys

part, lines, out = sys.argv[1], sys.argv[2], sys.argv[3]
rows = [json.loads(l) for l in open(lines) if l.strip()]
json.dump({"part": part, "rows": rows}, open(out, "w"), indent=1)
base = rows[0]
print("%-6s %-9s %-7s %9s %9s %11s %7s %9s" % (
    "ranks", "particles", "solver", "time [s]", "speed-up", "efficiency", "halo %", "reduce %"))
for r in rows:
    for k in ("cg", "newton"):
        d, t1 = r[k], base[k]["seconds"]
        # strong: t1 / (P t); weak (work grows with P): t1 / t
        sp = t1 / d["seconds"]
        eff = sp / r["ranks"] if part == "strong" else sp
        print("%-6d %-9d %-7s %9.2f %9.2f %11.2f %7.1f %9.1f" % (
            r["ranks"], r["particles"], k, d["seconds"], sp, eff,
            100 * d["halo_seconds"] / d["seconds"], 100 * d["reduction_seconds"] / d["seconds"]))
if part == "strong":
    sums = {(k, r[k]["checksum"]) for r in rows for k in ("cg", "newton")}
    print("checksums agree across rank counts" if len(sums) == 2 else "CHECKSUMS DIFFER ACROSS RANK COUNTS")
