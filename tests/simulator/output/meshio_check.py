# Reads a sinew results.xdmf with meshio's XDMF time-series reader (python3-meshio) and checks it
# against results.h5 read with h5py: the points, the hexahedra, the number of time steps and their
# times, and the displacement and cell fields of the first, a middle and the last frame. Every
# results_surface_<name>.xdmf beside it is checked the same way (triangles, the vertex positions
# of frame 0 as points, the displacement per frame).
# Usage: python3 meshio_check.py RESULTS.xdmf FRAMES POINTS CELLS [SURFACES]
import glob
import os
import sys

import h5py
import meshio
import numpy as np

path, frames, points, cells = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
expected_surfaces = int(sys.argv[5]) if len(sys.argv) > 5 else 0
folder = os.path.dirname(os.path.abspath(path))
failures = []
h5 = h5py.File(os.path.join(folder, "results.h5"), "r")
times = h5["/frames/time"][()]


def check_series(xdmf, cell_type, rest, connectivity, node_series, cell_series):
    with meshio.xdmf.TimeSeriesReader(xdmf) as reader:
        x, blocks = reader.read_points_cells()
        name = os.path.basename(xdmf)
        if reader.num_steps != len(times):
            failures.append(f"{name}: {reader.num_steps} time steps, expected {len(times)}")
            return
        if not np.array_equal(x, rest):
            failures.append(f"{name}: points differ from the HDF5 file's")
        if len(blocks) != 1 or blocks[0].type != cell_type:
            failures.append(f"{name}: cells {[b.type for b in blocks]}, expected one {cell_type}")
        elif not np.array_equal(blocks[0].data, connectivity):
            failures.append(f"{name}: {cell_type} connectivity differs from the HDF5 file's")
        for k in sorted({0, len(times) // 2, len(times) - 1}):
            t, point_data, cell_data = reader.read_data(k)
            if t != times[k]:
                failures.append(f"{name}: step {k} at t = {t}, the HDF5 file says {times[k]}")
            for field, series in node_series.items():
                if field not in point_data:
                    failures.append(f"{name}: step {k} lacks point field '{field}'")
                elif not np.array_equal(point_data[field], series[k]):
                    failures.append(f"{name}: step {k}: '{field}' differs from the HDF5 file's")
            for field, series in cell_series.items():
                if field not in cell_data:
                    failures.append(f"{name}: step {k} lacks cell field '{field}'")
                elif not np.array_equal(cell_data[field][0], series[k]):
                    failures.append(f"{name}: step {k}: '{field}' differs from the HDF5 file's")
        return x


if len(times) != frames:
    failures.append(f"the HDF5 file has {len(times)} frames, expected {frames}")
rest = h5["/mesh/rest_positions"][()]
conn = h5["/mesh/connectivity"][()]
if rest.shape != (points, 3) or conn.shape != (cells, 8):
    failures.append(f"the HDF5 mesh is {rest.shape} / {conn.shape}, expected {points} points and "
                    f"{cells} cells")
u = h5["/frames/displacement"]
cell_fields = {name: h5["/frames/" + name] for name in ["von_mises", "J", "energy_density"]
               if "/frames/" + name in h5}
cell_fields_static = {"material": [h5["/mesh/material"][()]] * len(times)}
check_series(path, "hexahedron", rest, conn, {"displacement": u}, {**cell_fields,
                                                                       **cell_fields_static})
surfaces = 0
for xdmf in sorted(glob.glob(os.path.join(folder, "results_surface_*.xdmf"))):
    name = os.path.basename(xdmf)[len("results_surface_"):-len(".xdmf")]
    group = h5["/surfaces/" + name]
    positions, displacement = group["positions"], group["displacement"]
    check_series(xdmf, "triangle", positions[0], group["triangles"][()],
                 {"displacement": displacement}, {})
    if not np.allclose(positions[-1] - positions[0], displacement[-1] - displacement[0],
                       rtol=0, atol=1e-12):
        failures.append(f"{name}: positions and displacement disagree")
    surfaces += 1
if surfaces != expected_surfaces:
    failures.append(f"{surfaces} results_surface_*.xdmf files, expected {expected_surfaces}")
if failures:
    print("FAILED: " + "; ".join(failures))
    sys.exit(1)
last = np.abs(u[len(times) - 1]).max()
print(f"meshio read {len(times)} time steps, {points} points, {cells} hexahedra "
      f"({', '.join(['displacement'] + list(cell_fields))}), {surfaces} surface file(s); "
      f"|u| max {last:.6g} m at t = {times[-1]:.6g} s")
