"""Leaf length, width and insertion angle by rank: synthetic plant vs the real PhenoTrack3D plant.

    python scripts/compare_synth_phenomenal.py [PHENOMENAL.json.gz] [--seeds 20]

Synthetic values are means over plants of ``maizeviz synth`` (default PlantShape); the real
ones are the Phenomenal pipeline's own measures (pm_length, pm_width_max, pm_insertion_angle).
"""

import argparse
from pathlib import Path

import numpy as np

from maizeviz.io.phenomenal import leaf_traits, load_phenomenal
from maizeviz.leaf.synth import PlantShape, plant_leaf_shapes

DEFAULT = Path(__file__).resolve().parents[1] / "maizeviz/resources/phenotrack3d/1649057232.json.gz"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("file", nargs="?", default=str(DEFAULT))
    ap.add_argument("--seeds", type=int, default=20)
    args = ap.parse_args()
    real = {t.rank: t for t in leaf_traits(load_phenomenal(args.file))}
    shapes = [plant_leaf_shapes(PlantShape(), rng=np.random.default_rng(s))
              for s in range(args.seeds)]
    print("rank | length cm synth / real | max width cm synth / real | insertion deg synth / real")
    rows = []
    for r in sorted(real):
        if r > len(shapes[0]):
            continue
        sl = np.mean([s[r - 1].length for s in shapes])
        sw = np.mean([s[r - 1].width for s in shapes])
        si = np.mean([s[r - 1].insertion_deg for s in shapes])
        t = real[r]
        rows.append((sl, t.length_cm, sw, t.width_max_cm, si, t.insertion_angle_deg, t.label))
        print(f"{r:4d} | {sl:6.1f} / {t.length_cm:6.1f} | {sw:5.1f} / {t.width_max_cm:5.1f} | "
              f"{si:5.1f} / {t.insertion_angle_deg:5.1f}  {t.label}")
    a = np.array([r[:6] for r in rows if r[6] == "mature_leaf"])
    print(f"mature leaves: length ratio synth/real {np.median(a[:, 0] / a[:, 1]):.2f} "
          f"(median), width {np.median(a[:, 2] / a[:, 3]):.2f}, insertion angle difference "
          f"{np.median(a[:, 4] - a[:, 5]):+.1f} deg")


if __name__ == "__main__":
    main()
