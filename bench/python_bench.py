#!/usr/bin/env python3
"""What stepping a scene from Python costs over sinew-simulate (docs/python.md, "Cost").

    PYTHONPATH=build/release/python python3 bench/python_bench.py MODEL [--steps N]
        [--per-call K] [--threads T] [--device cpu|cuda] [--simulate PATH]

MODEL is a forehead model (sinew-voxelize data/specs/forehead_1mm.yaml, or scripts/demo's
out/demo/forehead_1mm.h5); the scene is data/scenes/brow_raise.yaml on it, cut to N steps, with
only the first and last frames and no probes, so both sides time the same steps:
  - sinew-simulate: run_summary.json's time_per_step_s (its step loop's wall time / steps, with
    the last frame's writing), and the loop's `steps` stage alone (time_per_step_by_stage_s), the
    median of `--repeats` runs each;
  - Python: sinew.Simulation(scene).step(K) called N/K times, wall time / N, median of as many
    repeats (the engine built before the clock starts, as the tool's set-up is outside its loop);
  - displacements(): the median of 200 calls at the end (N × 3 float64 into a new array).
Prints one table (Markdown) for docs/python.md.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

# The same OpenMP wait policy on both sides: sinew-simulate chooses passive waiting unless
# OMP_WAIT_POLICY is set (common/threads.hpp), and the policy is read when the OpenMP runtime loads,
# before `import sinew` could set it, so this script starts itself again with it set.
if "OMP_WAIT_POLICY" not in os.environ:
    os.execve(sys.executable, [sys.executable] + sys.argv,
              dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))

import sinew  # noqa: E402

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
p.add_argument("model")
p.add_argument("--steps", type=int, default=2000)
p.add_argument("--per-call", type=int, default=100)
p.add_argument("--threads", type=int, default=0)
p.add_argument("--device", default="cpu")
p.add_argument("--repeats", type=int, default=3)
p.add_argument("--simulate", default=os.path.join(root, "build", "release", "simulator",
                                                  "sinew-simulate"))
a = p.parse_args()

base = sinew.Scene.load(os.path.join(root, "data", "scenes", "brow_raise.yaml")).with_model(a.model)
probe = sinew.Simulation(base, device=a.device, threads=a.threads)
scene = base.with_(duration=a.steps * probe.dt / probe.time_scaling * (1 - 1e-9),
                   probes=None, **{"output.interval": None, "output.probe_interval": None})
steps = sinew.Simulation(scene, device=a.device, threads=a.threads).steps_planned
del probe

tool, tool_steps, python, reads = [], [], [], []
with tempfile.TemporaryDirectory() as tmp:
    scene.save(os.path.join(tmp, "scene.yaml"))
    for r in range(a.repeats):
        out = os.path.join(tmp, f"cli{r}")
        cmd = [a.simulate, os.path.join(tmp, "scene.yaml"), "-o", out, "--device", a.device,
               "--quiet"] + (["--threads", str(a.threads)] if a.threads else [])
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        with open(os.path.join(out, "run_summary.json")) as f:
            summary = json.load(f)
        assert summary["steps_this_run"] == steps, summary["steps_this_run"]
        tool.append(summary["time_per_step_s"])
        tool_steps.append(summary["time_per_step_by_stage_s"]["steps"])

        sim = sinew.Simulation(scene, device=a.device, threads=a.threads)
        start = time.perf_counter()
        while sim.step_index < steps:
            sim.step(min(a.per_call, steps - sim.step_index))
        python.append((time.perf_counter() - start) / steps)
    for _ in range(200):
        start = time.perf_counter()
        sim.displacements()
        reads.append(time.perf_counter() - start)

t, py, rd = statistics.median(tool), statistics.median(python), statistics.median(reads)
ts = statistics.median(tool_steps)
print(f"model {a.model}: {sim.model.element_count} elements, {sim.model.node_count} nodes; "
      f"{sim.device}, {sim.precision}, OMP_WAIT_POLICY={os.environ['OMP_WAIT_POLICY']}; "
      f"{steps} steps, {a.per_call} per call, median of {a.repeats}")
print("| | per step | vs sinew-simulate |")
print("|---|---|---|")
print(f"| sinew-simulate (time_per_step_s) | {1e3 * t:.3f} ms | |")
print(f"| sinew-simulate, its steps stage alone | {1e3 * ts:.3f} ms | |")
print(f"| Simulation.step({a.per_call}) from Python | {1e3 * py:.3f} ms | "
      f"{100 * (py / t - 1):+.1f}% |")
print(f"| displacements() ({sim.model.node_count} × 3) | {1e3 * rd:.3f} ms | |")
print("runs:", ", ".join(f"{1e3 * x:.3f}" for x in tool), "ms (tool);",
      ", ".join(f"{1e3 * x:.3f}" for x in python), "ms (Python)", file=sys.stderr)
