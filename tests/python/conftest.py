"""Fixtures of the sinew module's tests (tests/python/CMakeLists.txt runs them under ctest).

The tools the module is compared with come from the environment the ctest entries set:
SINEW_SIMULATE, SINEW_GENERATE, SINEW_EXPORT, SINEW_VOXELIZE (empty without the voxelizer) and
SINEW_SOURCE (the repository, for data/).
"""
import os
import re
import shutil
import subprocess

import h5py
import numpy as np
import pytest
import yaml

SOURCE = os.environ.get("SINEW_SOURCE", os.path.join(os.path.dirname(__file__), "..", ".."))


def tool(name):
    path = os.environ.get(f"SINEW_{name.upper()}", "")
    if not path:
        pytest.skip(f"SINEW_{name.upper()} not set: skipped")
    return path


def run_tool(args, **kw):
    done = subprocess.run(args, capture_output=True, text=True, **kw)
    assert done.returncode == 0, f"{args}: {done.returncode}\n{done.stdout}\n{done.stderr}"
    return done


@pytest.fixture(scope="session")
def muscle_block(tmp_path_factory):
    """The muscle-driven block of data/scenes/muscle_block.yaml with its model generated beside it
    (the scene's own recipe), and sinew-simulate's results of it in cli/."""
    folder = tmp_path_factory.mktemp("muscle_block")
    shutil.copy(os.path.join(SOURCE, "data", "scenes", "muscle_block.yaml"), folder)
    run_tool([tool("generate"), "box", "--dims", "12", "3", "3", "--voxel-size", "0.002",
              "--material", "muscle:500000:0.49:11000", "--muscle", "flexor:muscle",
              "--fibre", "1", "0", "0", "-o", str(folder / "muscle_block.h5")])
    run_tool([tool("simulate"), str(folder / "muscle_block.yaml"), "-o", str(folder / "cli"),
              "--device", "cpu", "--quiet"])
    return folder


def h5_datasets(path):
    """Every dataset of an HDF5 file (virtual frame views resolved) by name."""
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                out[name] = obj[()]
        f.visititems(visit)
    return out


def assert_same_datasets(a, b, skip=()):
    da, db = h5_datasets(a), h5_datasets(b)
    assert sorted(da) == sorted(db)
    for name in da:
        if any(name.startswith(s) for s in skip):
            continue
        assert np.array_equal(da[name], db[name]), f"{name} differs between {a} and {b}"


class _Loader(yaml.SafeLoader):
    """PyYAML reads YAML 1.1, where 1.0e5 (no sign after e) is a string; sinew's reader (YAML 1.2)
    reads it as a number, as this loader does."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*\.[0-9_]*(?:[eE][-+]?[0-9]+)?|[0-9][0-9_]*[eE][-+]?[0-9]+)$"),
    list("-+0123456789"))


def yaml_load(path):
    with open(path, encoding="utf-8") as f:
        return yaml.load(f, Loader=_Loader)
