"""The central brow's rise against the frontalis' activation on the procedural forehead
(docs/python.md). Run from the repository after `SINEW_DEMO_RESOLUTION=2mm scripts/demo`:
    PYTHONPATH=build/release/python python3 docs/examples/brow_raise_sweep.py [MODEL] [PNG]"""
import sys

import matplotlib
matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt

import sinew

model = sys.argv[1] if len(sys.argv) > 1 else "out/demo/forehead_2mm.h5"
base = sinew.Scene.load("data/scenes/brow_raise.yaml").with_model(model)
peaks = [0.1, 0.2, 0.3, 0.4, 0.5]
rise = []
for a in peaks:
    scene = base.with_(**{"muscles.frontalis_left.peak": a, "muscles.frontalis_right.peak": a})
    brow = sinew.run(scene, device="auto").probes["brow_centre"]
    rise.append(1000 * brow["uy"].max())  # m → mm, the highest the brow got
    print(f"activation {a:.1f}: the brow rises {rise[-1]:.2f} mm")
plt.plot(peaks, rise, "o-")
plt.xlabel("frontalis activation (peak of its curve)")
plt.ylabel("central brow rise (mm)")
plt.title(f"Brow raise, procedural forehead, {1000 * sinew.Model.load(model).voxel_size:g} mm")
plt.grid(True)
plt.savefig(sys.argv[2] if len(sys.argv) > 2 else "brow_raise_sweep.png", dpi=110)
