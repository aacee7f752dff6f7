"""sinew.Scene: the scene reader's checks and messages, and key-path edits as sinew-sweep makes."""
import os

import pytest
import yaml

import sinew


def test_load_and_properties(muscle_block):
    s = sinew.Scene.load(str(muscle_block / "muscle_block.yaml"))
    assert s.file == str(muscle_block / "muscle_block.yaml")
    assert s.model_path == os.path.join(str(muscle_block), "muscle_block.h5")
    assert s.effects == ["elasticity", "hourglass", "damping", "muscles"]
    assert s.activated_muscles == ["flexor"]
    assert s.duration == 0.12 and s.precision == "double" and s.title == "muscle-driven block"


def test_dict_scene_is_the_file_scene(muscle_block):
    with open(muscle_block / "muscle_block.yaml") as f:
        as_dict = yaml.safe_load(f)
    s = sinew.Scene(as_dict, directory=muscle_block)
    assert s.file is None
    assert s.model_path == os.path.join(str(muscle_block), "muscle_block.h5")
    assert s.effects == sinew.Scene.load(str(muscle_block / "muscle_block.yaml")).effects


def test_with_sets_key_paths_and_checks_them(muscle_block):
    s = sinew.Scene.load(str(muscle_block / "muscle_block.yaml"))
    t = s.with_(**{"muscles.flexor.peak": 0.3, "damping": 20})
    assert yaml.safe_load(t.text)["muscles"]["flexor"]["peak"] == 0.3
    assert yaml.safe_load(t.text)["damping"] == 20
    assert yaml.safe_load(s.text)["muscles"]["flexor"]["peak"] == 0.15  # s is unchanged
    # None removes a key: its default applies (no probe interval: every step).
    assert "probe_interval" not in yaml.safe_load(
        s.with_(**{"output.probe_interval": None}).text)["output"]
    with pytest.raises(sinew.ConfigError) as e:
        s.with_(**{"muscles.flexor.peek": 0.3})
    assert "muscles.flexor.peek: unknown key 'peek'" in str(e.value)
    assert "[with_: muscles.flexor.peek = 0.3]" in str(e.value)
    assert e.value.field == "muscles.flexor.peek"
    with pytest.raises(sinew.ConfigError, match="muscles.flexor.peak"):
        s.with_(**{"muscles.flexor.peak": "lots"})
    with pytest.raises(sinew.ConfigError, match="out of range"):
        s.with_(**{"probes[7].name": "x"})
    with pytest.raises(sinew.ConfigError, match="cannot write"):
        s.with_(damping=object())


def test_bad_scenes_raise_the_readers_messages(muscle_block, tmp_path):
    with pytest.raises(sinew.ConfigError) as e:
        sinew.Scene({"model": "muscle_block.h5", "effects": ["elasticity"], "duration": 0.1,
                     "dampin": 3}, directory=muscle_block)
    assert str(e.value).startswith("scene (from a dict): dampin: unknown key 'dampin'")
    with pytest.raises(sinew.IoError):
        sinew.Scene.load(str(tmp_path / "missing.yaml"))
    (tmp_path / "broken.yaml").write_text("model: [unclosed\n")
    with pytest.raises(sinew.ConfigError, match="YAML syntax error"):
        sinew.Scene.load(str(tmp_path / "broken.yaml"))
    with pytest.raises(TypeError):
        sinew.Scene("muscle_block.yaml")  # a path goes through Scene.load


def test_save_writes_a_scene_that_runs_from_anywhere(muscle_block, tmp_path):
    s = sinew.Scene.load(str(muscle_block / "muscle_block.yaml")).with_(duration=0.01)
    s.save(tmp_path / "copy.yaml")
    t = sinew.Scene.load(str(tmp_path / "copy.yaml"))
    assert t.model_path == os.path.join(str(muscle_block), "muscle_block.h5")
    assert t.duration == 0.01
    m = sinew.Model.load(str(muscle_block / "muscle_block.h5"))
    assert s.with_model(m).model_path == m.path
