"""sinew.Results: a run's output folder (docs/results-format.md) as NumPy arrays."""
from __future__ import annotations

import csv
import json
import os
from typing import Dict, List, Optional, Tuple

import numpy as np

from . import _sinew

# Element fields by the scene's output.fields name and by dataset name.
_FIELDS = {"stress": "/frames/von_mises", "von_mises": "/frames/von_mises", "J": "/frames/J",
           "energy_density": "/frames/energy_density"}


class Results:
    """The results of a run: Results(folder) or Results("…/results.h5").

    times, steps           per frame: scene time (s) and engine step
    displacements(f)       N × 3 (frame f) or F × N × 3 (f None), m
    field(name, f)         per element: "von_mises" (Pa), "J", "energy_density" (J/m³)
    rest_positions         N × 3, m;  connectivity E × 8;  material E
    skin(f, surface)       (vertices V × 3 float32, m; triangles T × 3) of a visual surface
    probes                 name → {column: array} from probe_<name>.csv
    summary                run_summary.json as a dict
    export(glb=…, pc2=…, rest_obj=…, obj_sequence=…)   what sinew-export writes

    Arrays are read from the file when first asked for and kept (copies, writable). A file that
    is not sinew results raises sinew.FormatError with the readers' message.
    """

    def __init__(self, path: "str | os.PathLike[str]"):
        path = os.fspath(path)
        if os.path.isdir(path):
            self.folder = path
            self.file = os.path.join(path, "results.h5")
        else:
            self.folder = os.path.dirname(path) or "."
            self.file = path
        _sinew._results_check(self.file)
        self._cache: Dict[str, np.ndarray] = {}

    def _dataset(self, name: str, integers: bool = False) -> np.ndarray:
        if name not in self._cache:
            self._cache[name] = _sinew._results_dataset(self.file, name, integers)
        return self._cache[name]

    @property
    def times(self) -> np.ndarray:
        """F: each frame's scene time, s."""
        return self._dataset("/frames/time")

    @property
    def steps(self) -> np.ndarray:
        """F: each frame's engine step."""
        return self._dataset("/frames/step", integers=True)

    @property
    def frame_count(self) -> int:
        return int(self.times.shape[0])

    @property
    def rest_positions(self) -> np.ndarray:
        """N × 3, m."""
        return self._dataset("/mesh/rest_positions")

    @property
    def connectivity(self) -> np.ndarray:
        """E × 8 node ids, hex8 (VTK) order."""
        return self._dataset("/mesh/connectivity", integers=True)

    @property
    def material(self) -> np.ndarray:
        """E: each element's dominant material, −1 for none."""
        return self._dataset("/mesh/material", integers=True)

    def _frame(self, frame: int) -> int:
        count = self.frame_count
        f = frame + count if frame < 0 else frame
        if not 0 <= f < count:
            raise _sinew.ConfigError(f"{self.file}: frame {frame} out of range (the file has "
                                     f"{count} frames)")
        return f

    def _series(self, name: str, frame: Optional[int]) -> np.ndarray:
        if frame is None or name in self._cache:
            # Rows past the last complete frame (its time written last) are not results yet.
            data = self._dataset(name)[: self.frame_count]
            return data if frame is None else data[self._frame(frame)]
        # One frame: its virtual view (/frame_views/<f>/<series>), not the whole series.
        view = f"/frame_views/{self._frame(frame)}/{name.rsplit('/', 1)[1]}"
        return _sinew._results_dataset(self.file, view, False)

    def displacements(self, frame: Optional[int] = None) -> np.ndarray:
        """Node displacements u, m: N × 3 of one frame (negative counts from the end), or
        F × N × 3 of all (frame None)."""
        return self._series("/frames/displacement", frame)

    def positions(self, frame: int = -1) -> np.ndarray:
        """N × 3, m: rest + u of one frame."""
        return self.rest_positions + self.displacements(frame)

    @property
    def fields(self) -> List[str]:
        """The element fields the file has ("von_mises", "J", "energy_density")."""
        return [n for n, d in (("von_mises", "/frames/von_mises"), ("J", "/frames/J"),
                               ("energy_density", "/frames/energy_density"))
                if _sinew._results_has(self.file, d)]

    def field(self, name: str, frame: Optional[int] = None) -> np.ndarray:
        """An element field, E of one frame or F × E: "von_mises" (or "stress", Pa), "J",
        "energy_density" (J/m³ of reference volume)."""
        if name not in _FIELDS:
            raise _sinew.ConfigError(f"field: unknown field '{name}' (expected one of: "
                                     f"{', '.join(_FIELDS)})")
        return self._series(_FIELDS[name], frame)

    @property
    def surfaces(self) -> List[str]:
        """The visual surfaces stored (sorted)."""
        return list(_sinew._results_surfaces(self.file))

    def skin(self, frame: int = -1, surface: str = "") -> Tuple[np.ndarray, np.ndarray]:
        """(vertices V × 3 float32, m; triangles T × 3 int32) of a visual surface at a frame, as
        sinew-render and sinew-export read it: `surface` "" is the only one (or the volume's
        boundary when the file has none), "volume" the volume's boundary."""
        _, vertices, triangles = _sinew._results_skin(self.file, surface, frame)
        return vertices, triangles

    @property
    def probes(self) -> Dict[str, Dict[str, np.ndarray]]:
        """probe name → {column: float64 array} (time, step, ux, uy, uz or fx, fy, fz)."""
        out: Dict[str, Dict[str, np.ndarray]] = {}
        for entry in sorted(os.listdir(self.folder)):
            if entry.startswith("probe_") and entry.endswith(".csv"):
                out[entry[len("probe_"):-len(".csv")]] = _read_probe(
                    os.path.join(self.folder, entry))
        return out

    @property
    def summary(self) -> dict:
        """run_summary.json (docs/results-format.md): status, steps, Δt, wall time, energies…"""
        path = os.path.join(self.folder, "run_summary.json")
        try:
            with open(path, encoding="utf-8") as f:
                return json.load(f)
        except OSError as e:
            raise _sinew.IoError(f"{path}: cannot open the run summary: {e.strerror}") from None
        except json.JSONDecodeError as e:
            raise _sinew.FormatError(f"{path}: not JSON: {e}") from None

    def export(self, *, glb: Optional[str] = None, pc2: Optional[str] = None,
               rest_obj: Optional[str] = None, obj_sequence: Optional[str] = None,
               surface: str = "", up: str = "y", color: str = "none", fps: float = 0,
               time_scale: float = 0, linear: bool = False) -> List[str]:
        """Writes what sinew-export writes (docs/visual-output.md): a glTF 2.0 binary (glb), a
        PC2 point cache with its rest-pose OBJ (pc2 + rest_obj), an OBJ sequence (a folder).
        Returns the lines sinew-export prints."""
        return list(_sinew._export(self.file, surface, glb or "", pc2 or "", rest_obj or "",
                                   obj_sequence or "", up, color, float(fps), float(time_scale),
                                   linear))

    def __repr__(self) -> str:
        return f"<sinew.Results {self.file}, {self.frame_count} frames>"


def _read_probe(path: str) -> Dict[str, np.ndarray]:
    """A probe CSV (a header, then rows of numbers) as columns."""
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    if not rows:
        raise _sinew.FormatError(f"{path}: empty probe file (expected a header line)")
    header, body = rows[0], [r for r in rows[1:] if r]
    values = np.empty((len(body), len(header)), dtype=np.float64)
    for i, row in enumerate(body):
        if len(row) != len(header):
            raise _sinew.FormatError(f"{path}: row {i + 2} has {len(row)} values, the header "
                                     f"{len(header)} ({', '.join(header)})")
        try:
            values[i] = [float(x) for x in row]
        except ValueError:
            raise _sinew.FormatError(f"{path}: row {i + 2} is not numbers: "
                                     f"{','.join(row)[:80]}") from None
    return {name: values[:, k].copy() for k, name in enumerate(header)}
