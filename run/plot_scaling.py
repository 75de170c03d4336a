"""Draws scaling.json (from bench/scaling) as the paper's Fig. 8: speed-up
against threads, one line per schedule, with the ideal line."""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

data = json.load(open(sys.argv[1]))
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
schedules = sorted({r["schedule"] for r in data["rows"]})
for s in schedules:
    rows = [r for r in data["rows"] if r["schedule"] == s]
    p = [r["threads"] for r in rows]
    ax1.plot(p, [r["speedup"] for r in rows], "o-", label=s)
    ax2.plot(p, [r["seconds"] for r in rows], "o-", label=s)
top = max(r["threads"] for r in data["rows"])
ax1.plot([1, top], [1, top], "k--", lw=0.8, label="ideal")
ax1.set_xlabel("threads")
ax1.set_ylabel("speed-up")
ax2.set_xlabel("threads")
ax2.set_ylabel("seconds for %d CG iterations" % data["iterations"])
for ax in (ax1, ax2):
    ax.grid(alpha=0.3)
    ax.legend()
fig.suptitle("%d particles, %d iterations (paper's Fig. 8 / Table 2)" % (data["particles"], data["iterations"]))
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=100)
