# Opens a sinew results.xdmf with ParaView's XDMF reader (pvpython) and checks what a user would
# see: every frame as a time step, the hexahedral volume with its point and cell fields, and a
# displacement that grows from zero. Usage: pvpython paraview_check.py RESULTS.xdmf FRAMES POINTS CELLS
import sys

from paraview.simple import XDMFReader

path, frames, points, cells = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
reader = XDMFReader(FileNames=[path])
reader.UpdatePipelineInformation()
times = list(reader.TimestepValues)
failures = []
if len(times) != frames:
    failures.append(f"{len(times)} time steps, expected {frames}")

def magnitude_range(t):
    reader.UpdatePipeline(t)
    return reader.PointData["displacement"].GetRange(-1)

reader.UpdatePipeline(times[-1])
info = reader.GetDataInformation()
if info.GetNumberOfPoints() != points or info.GetNumberOfCells() != cells:
    failures.append(f"{info.GetNumberOfPoints()} points and {info.GetNumberOfCells()} cells, "
                    f"expected {points} and {cells}")
point_arrays = set(reader.PointData.keys())
cell_arrays = set(reader.CellData.keys())
for name in ["displacement"]:
    if name not in point_arrays:
        failures.append(f"point array '{name}' missing (has {sorted(point_arrays)})")
for name in ["material", "von_mises", "J"]:
    if name not in cell_arrays:
        failures.append(f"cell array '{name}' missing (has {sorted(cell_arrays)})")
if not failures:
    first, last = magnitude_range(times[0]), magnitude_range(times[-1])
    if first[1] != 0.0:
        failures.append(f"displacement at t = 0 is not zero: {first}")
    if not last[1] > 0.0:
        failures.append(f"displacement at the last frame is zero: {last}")
    print(f"ParaView read {len(times)} time steps, {points} points, {cells} cells; "
          f"|u| max {last[1]:.6g} m at t = {times[-1]:.6g} s")
if failures:
    print("FAILED: " + "; ".join(failures))
    sys.exit(1)
