"""sinew.run and sinew.Results against sinew-simulate's and sinew-export's own files."""
import csv
import json
import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

import sinew
from conftest import assert_same_datasets, run_tool, tool


@pytest.fixture(scope="module")
def python_run(muscle_block):
    scene = sinew.Scene.load(str(muscle_block / "muscle_block.yaml"))
    return sinew.run(scene, device="cpu", out=muscle_block / "py")


def test_run_gives_sinew_simulates_results_bit_for_bit(muscle_block, python_run):
    assert_same_datasets(muscle_block / "cli" / "results.h5", python_run.file)
    for probe in ("free_end", "clamp_force"):
        with open(muscle_block / "cli" / f"probe_{probe}.csv") as a, \
                open(os.path.join(python_run.folder, f"probe_{probe}.csv")) as b:
            assert a.read() == b.read()
    # The folder holds the scene it ran, with its model path absolute.
    again = sinew.Scene.load(os.path.join(python_run.folder, "scene.yaml"))
    assert again.model_path == str(muscle_block / "muscle_block.h5")


def test_results_arrays(muscle_block, python_run):
    r = python_run
    with h5py.File(muscle_block / "cli" / "results.h5", "r") as f:
        assert np.array_equal(r.times, f["/frames/time"][()])
        assert np.array_equal(r.steps, f["/frames/step"][()])
        assert np.array_equal(r.displacements(), f["/frames/displacement"][()])
        assert np.array_equal(r.displacements(3), f["/frames/displacement"][3])
        assert np.array_equal(r.displacements(-1), f["/frames/displacement"][-1])
        assert np.array_equal(r.field("von_mises"), f["/frames/von_mises"][()])
        assert np.array_equal(r.field("J", 2), f["/frames/J"][2])
        assert np.array_equal(r.connectivity, f["/mesh/connectivity"][()])
        assert np.array_equal(r.positions(-1),
                              f["/mesh/rest_positions"][()] + f["/frames/displacement"][-1])
    assert r.frame_count == 25 and sorted(r.fields) == ["J", "energy_density", "von_mises"]
    with open(muscle_block / "cli" / "probe_free_end.csv") as f:
        rows = list(csv.reader(f))
    probe = r.probes["free_end"]
    assert list(probe) == rows[0] == ["time", "step", "ux", "uy", "uz"]
    assert np.array_equal(probe["ux"], [float(row[2]) for row in rows[1:]])
    assert r.summary["status"] == "completed"
    assert r.summary == json.load(open(os.path.join(r.folder, "run_summary.json")))
    with pytest.raises(sinew.ConfigError, match="frame 25 out of range"):
        r.displacements(25)
    with pytest.raises(sinew.ConfigError, match="unknown field"):
        r.field("strain")


def test_skin_and_export_match_sinew_export(muscle_block, python_run, tmp_path):
    vertices, triangles = python_run.skin(-1)  # no visual surface: the volume's boundary
    assert vertices.dtype == np.float32 and triangles.shape[1] == 3
    # 12 × 3 × 3 voxels: 2 (12·3 + 12·3 + 3·3) faces, two triangles each.
    assert triangles.shape[0] == 2 * 2 * (36 + 36 + 9)
    lines = python_run.export(glb=str(tmp_path / "py.glb"), pc2=str(tmp_path / "py.pc2"),
                              rest_obj=str(tmp_path / "py.obj"))
    assert lines[0].endswith("25 frames (t = 0 .. 0.12 s)") or "25 frames" in lines[0]
    run_tool([tool("export"), python_run.file, "--glb", str(tmp_path / "cli.glb"), "--pc2",
              str(tmp_path / "cli.pc2"), "--rest-obj", str(tmp_path / "cli.obj")])
    for ext in ("glb", "pc2"):
        assert (tmp_path / f"py.{ext}").read_bytes() == (tmp_path / f"cli.{ext}").read_bytes()
    with pytest.raises(sinew.ConfigError, match="nothing to export"):
        python_run.export()
    with pytest.raises(sinew.ConfigError, match="--pc2 needs --rest-obj"):
        python_run.export(pc2=str(tmp_path / "x.pc2"))


def test_not_results_raise_the_readers_messages(muscle_block, tmp_path):
    with pytest.raises(sinew.FormatError, match="sinew-results|format"):
        sinew.Results(str(muscle_block / "muscle_block.h5"))
    with pytest.raises(sinew.IoError):
        sinew.Results(str(tmp_path / "none"))


def test_an_unstable_run_raises_and_keeps_its_frames(muscle_block, tmp_path):
    scene = sinew.Scene.load(str(muscle_block / "muscle_block.yaml")).with_(
        time_step={"mode": "fixed", "value": 2e-4, "force": True}, duration=0.05)
    with pytest.raises(sinew.UnstableError) as e:
        sinew.run(scene, device="cpu", out=tmp_path / "unstable")
    assert "step" in str(e.value)
    r = sinew.Results(tmp_path / "unstable")
    assert r.summary["status"] == "unstable"
    assert np.all(np.isfinite(r.displacements()))  # nothing non-finite written


CHILD = r"""
import sys, sinew
scene = sinew.Scene.load(sys.argv[1]).with_(duration=1000.0)
print("running", flush=True)
try:
    sinew.run(scene, device="cpu", out=sys.argv[2], force=True)
except KeyboardInterrupt:
    print("interrupted", sinew.Results(sys.argv[2]).summary["status"], flush=True)
"""


def test_ctrl_c_stops_a_run_at_a_step_with_a_checkpoint(muscle_block, tmp_path):
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(muscle_block / "muscle_block.yaml"),
                              str(tmp_path / "long")], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "running"
    time.sleep(1.0)
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=60)
    assert child.returncode == 0
    assert out.strip() == "interrupted interrupted"
    assert (tmp_path / "long" / "checkpoint.h5").exists()
    # It resumes from there with the tool.
    summary = json.load(open(tmp_path / "long" / "run_summary.json"))
    assert 0 < summary["steps_done"] < summary["steps_planned"]


@pytest.mark.skipif(not sinew.cuda_available(), reason="no CUDA device: the GPU variant skipped")
def test_run_on_the_gpu_matches_sinew_simulate_on_the_gpu(muscle_block, tmp_path):
    run_tool([tool("simulate"), str(muscle_block / "muscle_block.yaml"), "-o",
              str(tmp_path / "cli"), "--device", "cuda", "--quiet"])
    r = sinew.run(sinew.Scene.load(str(muscle_block / "muscle_block.yaml")), device="cuda",
                  out=tmp_path / "py")
    assert_same_datasets(tmp_path / "cli" / "results.h5", r.file)


def test_a_broken_probe_file_is_named(python_run, tmp_path):
    import shutil
    shutil.copy(python_run.file, tmp_path / "results.h5")
    (tmp_path / "probe_cut.csv").write_text("time,step,ux,uy,uz\n0,0,0,0,0\n0.001,56,1e-6\n")
    with pytest.raises(sinew.FormatError, match=r"probe_cut.csv: row 3 has 3 values, the header 5"):
        sinew.Results(tmp_path).probes
