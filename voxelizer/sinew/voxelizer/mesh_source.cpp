#include "sinew/voxelizer/mesh_source.hpp"

#include "sinew/voxelizer/primitives.hpp"

namespace sinew::voxelizer {

TriangleMesh load_mesh_source(const MeshSource& s) {
  if (s.kind == MeshSource::Kind::file) return load_mesh(s.path, s.transform);
  TriangleMesh m;
  switch (s.kind) {
    case MeshSource::Kind::sphere:
      m = make_sphere(s.centre, s.radii.x, s.subdivisions);
      break;
    case MeshSource::Kind::ellipsoid:
      m = make_ellipsoid(s.centre, s.radii, s.subdivisions);
      break;
    case MeshSource::Kind::box:
      m = make_box(s.box_lo, s.box_hi, s.subdivisions);
      break;
    case MeshSource::Kind::cylinder:
      m = make_cylinder(s.centre, s.radii.x, s.radii.y, s.subdivisions);
      break;
    case MeshSource::Kind::generated:
      if (s.generated) m = *s.generated;
      break;
    case MeshSource::Kind::file:
      break;
  }
  apply_transform(s.transform, m);
  m.source = s.describe();
  return m;
}

}  // namespace sinew::voxelizer
