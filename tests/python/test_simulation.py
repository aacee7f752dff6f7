"""sinew.Simulation: stepping from Python gives sinew-simulate's bits; state, steering, forces,
threads, Ctrl-C and bad input."""
import signal
import subprocess
import sys
import threading
import time

import h5py
import numpy as np
import pytest

import sinew


@pytest.fixture
def scene(muscle_block):
    return sinew.Scene.load(str(muscle_block / "muscle_block.yaml"))


def test_stepping_to_the_end_matches_sinew_simulate(muscle_block, scene):
    sim = sinew.Simulation(scene, device="cpu")
    with h5py.File(muscle_block / "cli" / "results.h5", "r") as f:
        steps = f["/frames/step"][()]
        frames = f["/frames/displacement"][()]
    for k, step in enumerate(steps):  # the frames, reached by steps of any size
        sim.step(int(step) - sim.step_index)
        assert np.array_equal(sim.displacements(), frames[k]), f"frame {k}"
    assert sim.step_index == sim.steps_planned
    assert sim.time == pytest.approx(sim.step_index * sim.dt)
    assert np.array_equal(sim.displacements([5, 3]), frames[-1][[5, 3]])
    assert sim.velocities().shape == (208, 3)
    assert np.array_equal(sim.positions(), sim.model.nodes + frames[-1])
    e = sim.energies()
    assert e["step"] == sim.step_index and e["kinetic"] >= 0
    fields = sim.element_fields()
    assert fields["J"].shape == (108,) and fields["cauchy"].shape == (108, 6)


def test_state_restores_bit_for_bit(scene):
    sim = sinew.Simulation(scene, device="cpu")
    sim.step(500)
    state = sim.state()
    assert state.step == 500 and state.u.shape == (208, 3)
    sim.step(700)
    first = sim.displacements()
    sim.restore(state)
    assert sim.step_index == 500
    sim.step(700)
    assert np.array_equal(sim.displacements(), first)
    other = sinew.Simulation(scene, device="cpu")
    other.restore(state)
    other.step(700)
    assert np.array_equal(other.displacements(), first)


def test_set_activation_within_the_peak_and_with_steering(scene):
    sim = sinew.Simulation(scene, device="cpu")
    assert sim.muscles == ["flexor"]
    with pytest.raises(sinew.ConfigError, match="no muscle 'nope'.*flexor"):
        sim.set_activation("nope", 0.1)
    with pytest.raises(sinew.ConfigError):
        sim.set_activation("flexor", 0.9)  # above the scene's peak 0.15: Δt was not planned for it
    steered = sinew.Simulation(scene, device="cpu", steering=True)
    assert steered.dt < sim.dt  # planned for full activation, as sinew-live plans it
    steered.set_activation("flexor", 0.9)
    assert steered.activation("flexor") == 0.9
    steered.step(3000)
    free_end = steered.model.node_sets["x_max"]
    assert steered.displacements(free_end)[:, 0].mean() < -1e-4  # the muscle shortens the block
    steered.set_activation("flexor", None)  # back to the curve
    assert steered.activation("flexor") is None


def test_set_force_pushes_nodes(scene):
    pushed = scene.with_(effects=["elasticity", "hourglass", "damping", "loads"], muscles=None)
    sim = sinew.Simulation(pushed, device="cpu")
    assert sim.force_slots == 1
    tip = sim.model.node_sets["x_max"]
    sim.set_force(tip, [0, 0, -0.01])
    sim.step(2000)
    assert sim.displacements(tip)[:, 2].mean() < -1e-5
    sim.clear_force()
    with pytest.raises(sinew.ConfigError, match="not finite"):
        sim.set_force(tip, [0, np.nan, 0])
    with pytest.raises(sinew.ConfigError, match="node id 208 out of range"):
        sim.set_force([0, 208], [0, 0, 1])
    with pytest.raises(sinew.ConfigError, match="3 components"):
        sim.set_force(tip, [0, 1])
    with pytest.raises(sinew.ConfigError, match="integers"):
        sim.set_force([0.5], [0, 0, 1])
    with pytest.raises(sinew.ConfigError, match="no force slots"):
        sinew.Simulation(scene, device="cpu").set_force(tip, [0, 0, 1])


def test_the_gil_is_released_while_stepping(scene):
    sim = sinew.Simulation(scene, device="cpu", threads=1)
    ticks, answers = [], []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(1)
            time.sleep(0.001)

    def read_while_stepping():  # a second thread's call while the first steps is refused
        while not stop.is_set():
            try:
                sim.displacements()
                answers.append("read")
            except RuntimeError as e:
                answers.append(str(e))
            time.sleep(0.001)

    threads = [threading.Thread(target=count), threading.Thread(target=read_while_stepping)]
    for t in threads:
        t.start()
    time.sleep(0.01)
    sim.step(sim.steps_planned)
    stop.set()
    for t in threads:
        t.join()
    assert len(ticks) > 10  # the other threads ran while this one stepped
    assert "this Simulation is busy in another thread (stepping)" in answers


def test_an_instability_raises_and_keeps_a_finite_state(scene):
    bad = scene.with_(time_step={"mode": "fixed", "value": 2e-4, "force": True})
    sim = sinew.Simulation(bad, device="cpu")
    with pytest.raises(sinew.UnstableError) as e:
        sim.step(1000)
    assert "step" in str(e.value)
    assert np.all(np.isfinite(sim.displacements()))


def test_close_frees_the_engine(scene):
    with sinew.Simulation(scene, device="cpu") as sim:
        sim.step(10)
        assert "step 10 of" in repr(sim)
    assert "closed" in repr(sim)
    with pytest.raises(RuntimeError, match="closed"):
        sim.step(1)
    with pytest.raises(RuntimeError, match="closed"):
        sim.displacements()
    assert sim.model.node_count == 208  # the model outlives the engine


def test_bad_arguments(scene):
    with pytest.raises(sinew.ConfigError, match="unknown device 'tpu'"):
        sinew.Simulation(scene, device="tpu")
    with pytest.raises(sinew.ConfigError, match="'float' or 'double'"):
        sinew.Simulation(scene, device="cpu", precision="half")
    sim = sinew.Simulation(scene, device="cpu", precision="float")
    assert sim.precision == "float"
    with pytest.raises(sinew.ConfigError, match="backwards"):
        sim.step(-1)


CHILD = r"""
import sys, sinew
sim = sinew.Simulation(sinew.Scene.load(sys.argv[1]), device="cpu", threads=1)
print("stepping", flush=True)
try:
    sim.step(10**9)
except KeyboardInterrupt:
    import numpy as np
    print("stopped", sim.step_index % 64 == 0, bool(np.isfinite(sim.displacements()).all()),
          flush=True)
"""


def test_ctrl_c_stops_step_at_a_step_boundary(muscle_block):
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(muscle_block / "muscle_block.yaml")],
                             stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "stepping"
    time.sleep(0.5)
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=60)
    assert child.returncode == 0 and out.strip() == "stopped True True"


@pytest.mark.skipif(not sinew.cuda_available(), reason="no CUDA device: the GPU variant skipped")
def test_gpu_stepping_matches_a_gpu_run(muscle_block, scene, tmp_path):
    r = sinew.run(scene, device="cuda", out=tmp_path / "gpu")
    sim = sinew.Simulation(scene, device="cuda")
    sim.step(sim.steps_planned)
    assert np.array_equal(sim.displacements(), r.displacements(-1))
