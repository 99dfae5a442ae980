"""Draw every built-in map to OUT/map_<name>.png.

Usage: python experiments/map_figures.py [--out docs/figures]   (default: results/figures)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib.pyplot as plt

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_io import out_folder, run_main  # noqa: E402

from rrtdrive.maps import BUILTIN_MAPS, builtin_map  # noqa: E402
from rrtdrive.plotting import draw_map, save_figure  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--out", default="results/figures", type=out_folder,
        help="output folder (docs/figures for the docs) (default: %(default)s)",
    )
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name in BUILTIN_MAPS:
        m = builtin_map(name)
        fig, ax = plt.subplots(figsize=(6, 6))
        draw_map(ax, m)
        ax.set_title(f"{name}: {len(m.obstacles)} obstacles")
        ax.legend(loc="upper right", fontsize=8)
        fig.tight_layout()
        save_figure(fig, out / f"map_{name}.png", dpi=90)
        print(out / f"map_{name}.png")


if __name__ == "__main__":
    sys.exit(run_main(main))  # Ctrl-C: one line and exit 130, no traceback
