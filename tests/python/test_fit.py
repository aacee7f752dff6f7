"""sinew.fit against sinew-fit: the same fit of the muscle block's free end, value for value."""
import json
import os

import numpy as np
import pytest

import sinew
from conftest import run_tool, tool


def test_fit_matches_sinew_fit(muscle_block, tmp_path):
    # The markers: the tool's own run of the block (its free_end probe), refitted with the
    # flexor alone; the base scene's curve is what the fit replaces.
    scene = str(muscle_block / "muscle_block.yaml")
    markers = str(muscle_block / "cli")
    run_tool([tool("fit"), scene, markers, "-o", str(tmp_path / "cli"), "--corrections", "1",
              "--step-activation", "0.15", "--response-ramp", "0.02", "--device", "cpu",
              "--quiet"])
    f = sinew.fit(sinew.Scene.load(scene), markers=markers, out=tmp_path / "py", corrections=1,
                  step_activation=0.15, response_ramp=0.02, device="cpu")
    assert f["muscles"] == ["flexor"] and f["activations"].shape == (1, len(f["knot_times"]))
    assert f["forward_runs"] == 2
    with open(tmp_path / "cli" / "fit_summary.json") as summary:
        assert f["rms_mm"] == json.load(summary)["marker_rms_mm"]
    with open(tmp_path / "cli" / "activations.csv") as a, \
            open(tmp_path / "py" / "activations.csv") as b:
        assert a.read() == b.read()
    assert isinstance(f["fitted_scene"], sinew.Scene)
    assert f["fitted_scene"].activated_muscles == ["flexor"]
    assert np.all(np.isfinite(f["frame_rms_mm"]))
    assert os.path.isdir(f["output_dir"])


def test_fit_refuses_what_sinew_fit_refuses(muscle_block, tmp_path):
    scene = sinew.Scene.load(str(muscle_block / "muscle_block.yaml"))
    with pytest.raises(sinew.ConfigError, match="markers .* or targets"):
        sinew.fit(scene, out=tmp_path / "x")
    with pytest.raises(sinew.ConfigError, match="nope"):
        sinew.fit(scene, markers=str(muscle_block / "cli"), out=tmp_path / "y", muscles=["nope"])
    assert not (tmp_path / "y").exists()
