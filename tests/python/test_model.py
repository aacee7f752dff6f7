"""sinew.Model and sinew.voxelize against the model file read by h5py and sinew-voxelize."""
import json
import os

import h5py
import numpy as np
import pytest

import sinew
from conftest import SOURCE, run_tool, tool, yaml_load


def test_arrays_match_the_file(muscle_block):
    path = str(muscle_block / "muscle_block.h5")
    m = sinew.Model.load(path)
    assert m.path == path
    with h5py.File(path, "r") as f:
        assert np.array_equal(m.node_lattice, f["/nodes/lattice"][()])
        assert np.array_equal(m.elements, f["/elements/nodes"][()])
        assert np.array_equal(m.material_fractions, f["/element_materials/fraction"][()])
        assert np.array_equal(m.origin, f["/grid/origin"][()])
    assert m.node_count == 208 and m.element_count == 108
    assert m.nodes.shape == (208, 3)
    # Rest positions: origin + h · lattice (model.hpp), here a box from the origin in 2 mm steps.
    expected = np.asarray(m.origin) + m.voxel_size * m.node_lattice
    assert np.array_equal(m.nodes, expected)
    assert m.voxel_size == 0.002 and tuple(m.dims) == (12, 3, 3)
    assert list(m.muscles) == ["flexor"]
    flexor = m.muscles["flexor"]
    assert flexor["fibres"].shape == (108, 3)
    assert np.array_equal(flexor["fibres"], np.tile([1.0, 0, 0], (108, 1)))
    assert m.materials[0]["name"] == "muscle"
    assert m.materials[0]["youngs_modulus"] == 500000
    assert "x_min" in m.node_sets
    assert json.loads(m.summary_json())["elements"] == 108
    assert "108" in m.summary()


def test_views_are_read_only_and_outlive_the_model(muscle_block):
    m = sinew.Model.load(str(muscle_block / "muscle_block.h5"))
    elements = m.elements
    with pytest.raises(ValueError, match="read-only"):
        elements[0, 0] = 7
    with pytest.raises(ValueError, match="read-only"):
        m.muscles["flexor"]["fractions"][0] = 0.5
    first = elements[0].copy()
    del m  # the view keeps the model alive
    assert np.array_equal(elements[0], first)
    nodes = sinew.Model.load(str(muscle_block / "muscle_block.h5")).nodes
    nodes[0, 0] = 1.0  # a copy: writable


def test_save_round_trip_is_byte_identical(muscle_block, tmp_path):
    src = str(muscle_block / "muscle_block.h5")
    m = sinew.Model.load(src)
    out = str(tmp_path / "again.h5")
    m.save(out)
    assert m.path == out
    with open(src, "rb") as a, open(out, "rb") as b:
        assert a.read() == b.read()


def test_not_a_model_raises_the_readers_message(muscle_block, tmp_path):
    text = tmp_path / "notes.h5"
    text.write_text("not a model")
    with pytest.raises(sinew.FormatError) as e:
        sinew.Model.load(str(text))
    assert str(e.value) == f"{text}: not an HDF5 file (no HDF5 signature found)"
    assert e.value.file == str(text)
    assert isinstance(e.value, ValueError)
    with pytest.raises(sinew.IoError) as e:
        sinew.Model.load(str(tmp_path / "missing.h5"))
    assert isinstance(e.value, OSError)
    # A results file is HDF5, but not a model: the reader says which format it expected.
    with pytest.raises(sinew.FormatError, match="not a sinew model file"):
        sinew.Model.load(str(muscle_block / "cli" / "results.h5"))


@pytest.mark.skipif(not sinew.has_voxelizer, reason="built without the voxelizer: skipped")
def test_voxelize_matches_sinew_voxelize(tmp_path):
    spec = yaml_load(os.path.join(SOURCE, "data", "specs", "layered_box.yaml"))
    spec["resolution"] = {"voxel_size": 2}  # mm: a quick model
    spec_file = tmp_path / "box.json"  # JSON is YAML: the tool reads it as it is
    spec_file.write_text(json.dumps(spec))
    run_tool([tool("voxelize"), str(spec_file), "-o", str(tmp_path / "cli.h5"), "--quiet"])
    from_dict = sinew.voxelize(spec, out=tmp_path / "py.h5")
    from_file = sinew.voxelize(str(spec_file))
    assert from_file.path is None and from_dict.path == str(tmp_path / "py.h5")
    cli = sinew.Model.load(str(tmp_path / "cli.h5"))
    for m in (from_dict, from_file):
        assert np.array_equal(m.elements, cli.elements)
        assert np.array_equal(m.nodes, cli.nodes)
        assert np.array_equal(m.material_fractions, cli.material_fractions)
        assert np.array_equal(m.rigid_nodes, cli.rigid_nodes)
        assert list(m.node_sets) == list(cli.node_sets)
    assert json.loads(from_dict.voxelize_summary)["elements"] == cli.element_count
    spec["resolution"] = {"voxel_sise": 2}
    with pytest.raises(sinew.ConfigError, match="voxel_sise"):
        sinew.voxelize(spec)
