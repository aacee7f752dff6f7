"""sinew from Python: voxel finite-element face models, their scenes, runs and results as NumPy.

    import sinew
    scene = sinew.Scene.load("data/scenes/forehead_brow_raise.yaml")
    results = sinew.run(scene.with_(**{"activations.frontalis_left.peak": 0.6}), device="cpu")
    print(results.times, results.displacements(-1).shape)

    sim = sinew.Simulation(scene, device="cpu")
    sim.step(100)                      # the GIL is released; Ctrl-C stops at a step boundary
    u = sim.displacements()            # N × 3 NumPy array, m

The same library calls as the command-line tools (sinew-voxelize, sinew-simulate, sinew-export),
with their checks and their messages: errors are sinew.Error subclasses (InputError, IoError,
UnstableError, ResourceError) whose str() is the tools' message. docs/python.md has the guide and
a worked study.
"""
from __future__ import annotations

import json as _json
import os as _os
import tempfile as _tempfile
from typing import Any, Mapping, Optional, Union

from . import _sinew
from ._sinew import (  # noqa: F401  (re-exported)
    ConfigError,
    Error,
    FormatError,
    GeometryError,
    InputError,
    IoError,
    Model,
    ResourceError,
    State,
    UnstableError,
    cuda_available,
    has_voxelizer,
)
from ._results import Results

__all__ = [
    "ConfigError", "Error", "FormatError", "GeometryError", "InputError", "IoError", "Model",
    "ResourceError", "Results", "Scene", "Simulation", "State", "UnstableError", "cuda_available",
    "has_voxelizer",
    "fit", "run", "voxelize",
]

PathLike = Union[str, "_os.PathLike[str]"]


def _json_value(value: Any) -> str:
    """A Python value as one line of JSON, which the YAML reader reads as the same value."""
    def default(v: Any) -> Any:
        if hasattr(v, "tolist"):  # NumPy scalars and arrays
            return v.tolist()
        raise ConfigError(f"cannot write {type(v).__name__} {v!r} into a scene or spec "
                          "(numbers, strings, booleans, lists and dicts only)")
    return _json.dumps(value, default=default, allow_nan=False)


def voxelize(spec: Union[PathLike, Mapping[str, Any]], *, out: Optional[PathLike] = None,
             directory: Optional[PathLike] = None, threads: int = 0,
             force: bool = False) -> Model:
    """Builds a model from a voxelizer spec (docs/voxelizer.md): what sinew-voxelize does.

    spec: a spec file's path, or the spec as a dict (relative mesh paths then resolve against
    `directory`, default the current folder). out: where to write the model file (default: the
    model stays in memory; Model.save writes it later). threads: OpenMP threads (0: all).
    force: go past the bounds on the meshes with a warning each (sinew-voxelize --force).
    The GIL is released while it works. Raises sinew.ConfigError, GeometryError, IoError, ...
    """
    if isinstance(spec, Mapping):
        text = _json_value(dict(spec))
        file = _os.path.join(_os.fspath(directory or "."), "spec (from a dict)")
    else:
        file = _os.fspath(spec)
        try:
            with open(file, encoding="utf-8") as f:
                text = f.read()
        except OSError as e:
            raise IoError(f"{file}: cannot open the spec file: {e.strerror}") from None
    return _sinew._voxelize(text, file, _os.fspath(out) if out is not None else "", threads,
                            force)


class Scene:
    """A scene (docs/scene-format.md): which model, which effects, muscles' curves, outputs.

    Scene.load(path) reads a scene file; Scene(dict, directory=".") makes one from a dict (its
    relative model path resolves against `directory`). Either is checked by the scene reader of
    sinew-simulate at once, so a wrong key raises sinew.ConfigError with the tool's message.
    Scenes are immutable: with_() returns an edited copy.
    """

    __slots__ = ("_scene",)

    def __init__(self, source: Mapping[str, Any], directory: Optional[PathLike] = None):
        if isinstance(source, _sinew._Scene):
            self._scene = source
            return
        if not isinstance(source, Mapping):
            raise TypeError("Scene(dict): give the scene as a dict, or use Scene.load(path) or "
                            "Scene.from_yaml(text)")
        self._scene = _sinew._Scene(_json_value(dict(source)), "",
                                    _os.fspath(directory or "."))

    @classmethod
    def load(cls, path: PathLike) -> "Scene":
        """Reads and checks a scene file."""
        return cls(_sinew._Scene.load(_os.fspath(path)))

    @classmethod
    def from_yaml(cls, text: str, directory: Optional[PathLike] = None) -> "Scene":
        """A scene from YAML text (its relative model path resolves against `directory`)."""
        return cls(_sinew._Scene(text, "", _os.fspath(directory or ".")))

    def with_(self, values: Optional[Mapping[str, Any]] = None, /, **paths: Any) -> "Scene":
        """A copy with values set at key paths, as sinew-sweep's grids set them:

            scene.with_(**{"activations.frontalis_left.peak": 0.6, "damping": 50})
            scene.with_({"output.interval": 0.01})

        A key path is "key", "parent.key" or "list[2].key"; None removes the key (its default
        applies). The result is checked like any scene: a wrong path or value raises
        sinew.ConfigError naming the key.
        """
        merged = dict(values or {})
        merged.update(paths)
        if not merged:
            return self
        pairs = [(str(k), _json_value(v)) for k, v in merged.items()]
        return Scene(self._scene._replaced(pairs))

    def with_model(self, model: Union[PathLike, Model]) -> "Scene":
        """A copy that runs `model` (a path, or a Model that has a file: Model.save first)."""
        if isinstance(model, Model):
            if model.path is None:
                raise ConfigError("with_model: this Model is only in memory; save it first "
                                  "(model.save(path))")
            model = model.path
        return self.with_(model=_os.path.abspath(_os.fspath(model)))

    def save(self, path: PathLike) -> None:
        """Writes the scene as YAML, its model path made absolute (it runs from any folder)."""
        text = self.with_model(self.model_path).text
        path = _os.fspath(path)
        tmp = f"{path}.tmp-{_os.getpid()}"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
        _os.replace(tmp, path)

    text = property(lambda self: self._scene.text, doc="The scene as YAML text.")
    file = property(lambda self: self._scene.file, doc="The file it was read from, or None.")
    directory = property(lambda self: self._scene.directory,
                         doc="The folder its relative model path resolves against.")
    model_path = property(lambda self: self._scene.model_path, doc="The model file it runs.")
    title = property(lambda self: self._scene.title)
    duration = property(lambda self: self._scene.duration, doc="s of scene time")
    time_scaling = property(lambda self: self._scene.time_scaling)
    precision = property(lambda self: self._scene.precision, doc="'float' or 'double'")
    effects = property(lambda self: list(self._scene.effects), doc="The effects it simulates.")
    activated_muscles = property(lambda self: list(self._scene.activated_muscles),
                                 doc="The muscles its activations name, in order.")

    def __repr__(self) -> str:
        where = self.file or "from a dict"
        return f"<sinew.Scene {self.title or '(untitled)'!r}, {where}, model {self.model_path}>"


def _scene_of(scene: Union[Scene, PathLike]) -> Scene:
    return scene if isinstance(scene, Scene) else Scene.load(scene)


def run(scene: Union[Scene, PathLike], *, device: str = "auto", precision: Optional[str] = None,
        out: Optional[PathLike] = None, threads: int = 0, progress: bool = False,
        force: bool = False, restart: Optional[PathLike] = None, checkpoint_every: int = 0,
        explain: bool = False) -> Results:
    """Runs a scene as sinew-simulate does and returns its Results.

    out: the output folder (default: a new temporary folder, Results.folder); it receives
    scene.yaml (the scene run, model path absolute), results.h5 + .xdmf, probe CSVs,
    run_summary.json, checkpoint.h5 when asked or interrupted. device: "cpu", "cuda" or "auto".
    precision: "float" or "double" (None: the scene's). threads: OpenMP threads (0: OpenMP's
    default). force: run past the step/frame/row limits. restart: a checkpoint to resume from.

    The GIL is released while it runs. Ctrl-C stops the run at a step boundary with a checkpoint
    (status "interrupted") and raises KeyboardInterrupt. An instability writes the frames so far
    and the summary (status "unstable") and raises sinew.UnstableError.
    """
    s = _scene_of(scene)
    folder = _os.fspath(out) if out is not None else _tempfile.mkdtemp(prefix="sinew-run-")
    done = _sinew._run(s._scene, folder, device, precision, threads, progress, force,
                       _os.fspath(restart) if restart is not None else "", checkpoint_every,
                       explain)
    return Results(done)


class Simulation(_sinew._Simulation):
    """A scene's simulation, stepped from Python.

        sim = sinew.Simulation(scene, device="cpu")
        while sim.step_index < sim.steps_planned:
            sim.step(100)
            u = sim.displacements()        # N × 3, m

    Without steering, its time step and every step are sinew-simulate's: stepping it through
    steps_planned gives sinew-simulate's displacements bit for bit. steering=True plans the time
    step for any activation in [0, 1] (as sinew-live does), so set_activation may exceed the
    scene's peaks. set_force needs `loads` among the scene's effects (force_slots slots, each one
    force on a node set).

    step(n) releases the GIL and checks Ctrl-C between the engine's batches (KeyboardInterrupt
    at a step boundary; the state stays consistent). An instability raises sinew.UnstableError
    and leaves the state at the step where it was found.
    """

    def __init__(self, scene: Union[Scene, PathLike], *, device: str = "auto",
                 precision: Optional[str] = None, threads: int = 0, steering: bool = False,
                 force_slots: int = 1):
        s = _scene_of(scene)
        super().__init__(s._scene, device, precision, threads, steering, force_slots)
        self.scene = s

    def positions(self):
        """N × 3, m: the nodes' current positions (rest + displacements)."""
        return self.model.nodes + self.displacements()

    def __enter__(self) -> "Simulation":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        try:
            where = f"step {self.step_index} of {self.steps_planned}"
        except RuntimeError as e:  # closed, or stepping in another thread
            where = str(e).replace("this Simulation is ", "")
        return (f"<sinew.Simulation {self.model.element_count} elements on {self.device}, "
                f"{self.precision}, {where}>")


def fit(scene: Union[Scene, PathLike], *, out: PathLike, markers: Optional[PathLike] = None,
        targets: Optional[PathLike] = None, target_surface: str = "", target_markers: int = 200,
        muscles: Optional[list] = None, jaw: str = "auto", max_activation: float = 1.0,
        knot_interval: float = 0.0, step_activation: float = 0.3, response_ramp: float = 0.0,
        smoothing: float = 1e-3, effort: float = 0.0, corrections: int = 4,
        marker_unit: float = 0.0, sample_interval: float = 0.0,
        cache: Optional[PathLike] = None, device: str = "cpu", threads: int = 0) -> dict:
    """Fits the rig's muscle activations (and the jaw's keys) to markers: what sinew-fit does
    (docs/fit.md), with its options by the same names.

    markers: a marker CSV, or a run's output folder (its displacement probes become markers);
    or targets: a target-shape manifest (sculpts of a visual surface at key times). out: the
    output folder (fitted_scene.yaml, activations.csv, marker_error.csv, fit_summary.json,
    runs/), written under a temporary name and renamed at the end. Returns the fit as a dict:
    muscles, knot_times and activations (K × knots) as arrays, the jaw's keys and values, the
    marker error per frame and per marker (mm), rms_mm, max_mm, the runs made and their wall
    times, and fitted_scene (a sinew.Scene that replays the fit). Ctrl-C stops the fit's run at
    a step boundary and raises KeyboardInterrupt; nothing is left under `out`.
    """
    if (markers is None) == (targets is None):
        raise ConfigError("fit: give markers (a CSV or a run's folder) or targets (a manifest), "
                          "one of them")
    s = _scene_of(scene)
    o = _sinew._FitOptions()
    with _tempfile.TemporaryDirectory(prefix="sinew-fit-") as tmp:
        o.scene_path = _os.path.join(tmp, "scene.yaml")
        s.save(o.scene_path)
        o.markers_path = _os.fspath(markers) if markers is not None else ""
        o.targets_path = _os.fspath(targets) if targets is not None else ""
        o.target_surface = target_surface
        o.target_markers = target_markers
        o.output_dir = _os.fspath(out)
        o.muscles = list(muscles or [])
        o.jaw = jaw
        o.max_activation = max_activation
        o.knot_interval = knot_interval
        o.step_activation = step_activation
        o.response_ramp = response_ramp
        o.smoothing = smoothing
        o.effort = effort
        o.corrections = corrections
        o.marker_unit = marker_unit
        o.sample_interval = sample_interval
        o.cache_dir = _os.fspath(cache) if cache is not None else ""
        o.device = device
        o.threads = threads
        result = _sinew._fit(o)
    result["fitted_scene"] = Scene.load(_os.path.join(result["output_dir"], "fitted_scene.yaml"))
    return result
