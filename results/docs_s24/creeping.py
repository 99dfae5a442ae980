"""Creeping time (simulation steps with 0 < |v| < 0.03 m/s, times the step) of the
trajectory CSVs written by `rrtdrive simulate ... --trajectory T.csv`."""
import sys, numpy as np
for f in sys.argv[1:]:
    d = np.genfromtxt(f, delimiter=",", names=True)
    t, v = d["t"], d["speed"]
    dt = float(np.median(np.diff(t)))
    creep = np.count_nonzero((np.abs(v) > 0) & (np.abs(v) < 0.03)) * dt
    print(f"{f}: {len(t)} rows, dt {dt:.3f} s, end t {t[-1]:.2f} s, creeping {creep:.2f} s")
