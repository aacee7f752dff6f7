#include "sinew/voxelizer/fractions.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "sinew/common/error.hpp"

namespace sinew::voxelizer {

namespace {

// The corners of triangle t of mesh.
std::array<Vec3d, 3> corners(const TriangleMesh& mesh, std::size_t t) {
  const auto& tri = mesh.triangles[t];
  return {mesh.vertices[static_cast<std::size_t>(tri[0])],
          mesh.vertices[static_cast<std::size_t>(tri[1])],
          mesh.vertices[static_cast<std::size_t>(tri[2])]};
}

// Unit normal of the counter-clockwise triangle (a, b, c); `degenerate` when it has no area.
Vec3d unit_normal(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& degenerate) {
  const Vec3d n = cross(b - a, c - a);
  const double len = norm(n);
  return len > 0 ? (1.0 / len) * n : degenerate;
}

}  // namespace

SignedField::SignedField(const TriangleMesh& mesh, bool watertight, bool closed)
    : mesh_(mesh),
      winding_(mesh),
      distance_(mesh),
      bounds_(bounding_box(mesh)),
      watertight_(watertight),
      closed_(closed) {
  if (!watertight_) return;
  const std::size_t nt = mesh_.triangles.size();
  face_normal_.resize(nt);
  edge_normal_.assign(nt, {Vec3d{0, 0, 0}, Vec3d{0, 0, 0}, Vec3d{0, 0, 0}});
  vertex_normal_.assign(mesh_.vertices.size(), Vec3d{0, 0, 0});
  std::map<std::pair<std::int32_t, std::int32_t>, Vec3d> edge_sum;
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tri = mesh_.triangles[t];
    const auto [a, b, c] = corners(mesh_, t);
    const Vec3d n = unit_normal(a, b, c, Vec3d{0, 0, 0});
    face_normal_[t] = n;
    const Vec3d* v[3] = {&a, &b, &c};
    for (int k = 0; k < 3; ++k) {
      const Vec3d e1 = *v[(k + 1) % 3] - *v[k], e2 = *v[(k + 2) % 3] - *v[k];
      const double l1 = norm(e1), l2 = norm(e2);
      const double cosang =
          (l1 > 0 && l2 > 0) ? std::clamp(dot(e1, e2) / (l1 * l2), -1.0, 1.0) : 1.0;
      vertex_normal_[static_cast<std::size_t>(tri[k])] += std::acos(cosang) * n;
      const auto key = std::minmax(tri[k], tri[(k + 1) % 3]);
      edge_sum[{key.first, key.second}] += n;
    }
  }
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tri = mesh_.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const auto key = std::minmax(tri[k], tri[(k + 1) % 3]);
      edge_normal_[t][static_cast<std::size_t>(k)] = edge_sum[{key.first, key.second}];
    }
  }
}

bool SignedField::pseudonormal_inside(const Vec3d& p, const DistanceQuery::Hit& hit) const {
  const auto t = static_cast<std::size_t>(hit.triangle);
  const auto& tri = mesh_.triangles[t];
  const auto [a, b, c] = corners(mesh_, t);
  // Barycentric coordinates of the closest point decide its feature.
  const Vec3d v0 = b - a, v1 = c - a, v2 = hit.point - a;
  const double d00 = dot(v0, v0), d01 = dot(v0, v1), d11 = dot(v1, v1);
  const double d20 = dot(v2, v0), d21 = dot(v2, v1);
  const double den = d00 * d11 - d01 * d01;
  double bary[3] = {1.0 / 3, 1.0 / 3, 1.0 / 3};
  if (den > 0) {
    bary[1] = (d11 * d20 - d01 * d21) / den;
    bary[2] = (d00 * d21 - d01 * d20) / den;
    bary[0] = 1.0 - bary[1] - bary[2];
  }
  constexpr double eps = 1e-9;
  int zeros = 0;
  for (double x : bary) zeros += x <= eps ? 1 : 0;
  Vec3d n = face_normal_[t];
  if (zeros >= 2) {
    int k = 0;
    for (int i = 1; i < 3; ++i)
      if (bary[i] > bary[k]) k = i;
    n = vertex_normal_[static_cast<std::size_t>(tri[k])];
  } else if (zeros == 1) {
    int k = 0;
    for (int i = 1; i < 3; ++i)
      if (bary[i] < bary[k]) k = i;
    // The edge opposite corner k runs from corner k+1 to k+2: edge index (k + 1) % 3.
    n = edge_normal_[t][static_cast<std::size_t>((k + 1) % 3)];
  }
  return dot(p - hit.point, n) < 0;
}

bool SignedField::inside(const Vec3d& p) const {
  if (watertight_) return pseudonormal_inside(p, distance_.closest(p));
  // inside() re-evaluates near 1/2 at a higher accuracy; the raw value at beta 2 can be 6e-3 off.
  return winding_.inside(p);
}

SignedField::Sample SignedField::operator()(const Vec3d& p) const {
  Sample s;
  const auto hit = distance_.closest(p);
  const double scale = norm(bounds_.hi - bounds_.lo);
  const bool on_surface = !(hit.distance > 1e-12 * scale);
  bool inside;
  if (watertight_ && !on_surface) {
    inside = pseudonormal_inside(p, hit);
    s.winding = inside ? 1.0 : 0.0;
  } else {
    s.winding = winding_(p);
    inside = winding_.inside(p);
  }
  s.triangle = hit.triangle;
  s.value = inside ? hit.distance : -hit.distance;
  if (!on_surface) {
    const Vec3d d = (1.0 / hit.distance) * (p - hit.point);
    s.gradient = inside ? d : -d;
  } else {
    // On the surface: the triangle normal, pointing to where the winding number says inside.
    const auto [a, b, c] = corners(mesh_, static_cast<std::size_t>(hit.triangle));
    const Vec3d n = unit_normal(a, b, c, Vec3d{0, 0, 1});
    const double step = 1e-6 * scale;
    s.gradient = winding_(p + step * n) >= winding_(p - step * n) ? n : -n;
  }
  return s;
}

double cube_fraction_below(const Vec3d& n_in, double tau) {
  // Flip negative components (u_i -> 1 - u_i) so that all n_i >= 0.
  double n[3] = {n_in.x, n_in.y, n_in.z};
  for (double& c : n) {
    if (c < 0) {
      tau -= c;
      c = -c;
    }
  }
  const double big = std::max({n[0], n[1], n[2]});
  if (big <= 0) return tau > 0 ? 1.0 : 0.0;
  if (tau <= 0) return 0.0;
  if (tau >= n[0] + n[1] + n[2]) return 1.0;
  // Components negligible next to the largest act like zero (the error is below 1e-9 of the cell).
  double m[3] = {0, 0, 0};
  int k = 0;
  for (double c : n)
    if (c > 1e-9 * big) m[k++] = c;
  double sum = 0;
  if (k == 1) return std::clamp(tau / m[0], 0.0, 1.0);
  const int corners = 1 << k;
  for (int v = 0; v < corners; ++v) {
    double dot = 0;
    int bits = 0;
    for (int i = 0; i < k; ++i) {
      if (v & (1 << i)) {
        dot += m[i];
        ++bits;
      }
    }
    const double x = tau - dot;
    if (x <= 0) continue;
    const double p = k == 2 ? x * x : x * x * x;
    sum += (bits % 2 ? -p : p);
  }
  const double denom = k == 2 ? 2.0 * m[0] * m[1] : 6.0 * m[0] * m[1] * m[2];
  return std::clamp(sum / denom, 0.0, 1.0);
}

namespace {

constexpr double kSqrt3 = 1.7320508075688772;
constexpr int kBlock = 8;  // voxels per block side at the top level
constexpr int kSubSamples = 4;

// Field states at one cell centre. A field that does not cross a cell does not cross its
// children either (1-Lipschitz), so children inherit it without a new query.
struct CellState {
  bool uniform = false;
  int label = 0;  // when uniform
  // Depth: the layer (-1 above the skin) when not crossing; the sample when crossing.
  bool depth_crossing = false;
  int depth_layer = 0;
  SignedField::Sample depth;
  // Inner surface and bodies: 0 outside, 1 inside, 2 crossing (then the sample is fresh).
  char inner_state = 0;
  SignedField::Sample inner;
  std::vector<char> body_state;
  std::vector<SignedField::Sample> body_sample;
};

class Integrator {
 public:
  explicit Integrator(const FractionProblem& p) : p_(p) {}

  std::int64_t evaluations = 0;

  int layer_of(double depth) const {
    if (depth < 0) return -1;
    int i = 0;
    while (i < static_cast<int>(p_.layer_bottoms.size()) && depth >= p_.layer_bottoms[i]) ++i;
    return i;
  }

  // layer: -1 above the skin, else the layer index by depth.
  int label_for(int layer, bool inner_in, const std::vector<char>& body_in) const {
    if (layer < 0 || inner_in) return 0;
    for (int b = static_cast<int>(p_.bodies.size()) - 1; b >= 0; --b) {
      if (body_in[static_cast<std::size_t>(b)]) return p_.bodies[static_cast<std::size_t>(b)].label;
    }
    return 1 + layer;
  }

  static bool box_overlaps(const Vec3d& c, double a, const Vec3d& lo, const Vec3d& hi) {
    return c.x + a >= lo.x && c.x - a <= hi.x && c.y + a >= lo.y && c.y - a <= hi.y &&
           c.z + a >= lo.z && c.z - a <= hi.z;
  }

  bool depth_crosses(double d, double r) const {
    if (std::abs(d) < r) return true;
    for (double b : p_.layer_bottoms)
      if (std::abs(d - b) < r) return true;
    return false;
  }
  bool open_field_ambiguous(const SignedField& f, const SignedField::Sample& s, bool leaf) const {
    return !leaf && !f.closed() && s.winding > 0.1 && s.winding < 0.9;
  }

  // Evaluates the fields at cell centre c (half side a); fields not crossing the parent cell are
  // inherited. leaf: no further subdivision follows, so only distance-based crossings count.
  CellState evaluate(const Vec3d& c, double a, bool leaf, const CellState* parent) {
    CellState st;
    const double r = a * kSqrt3;
    const std::size_t nb = p_.bodies.size();
    if (parent && !parent->depth_crossing) {
      st.depth_layer = parent->depth_layer;
    } else {
      st.depth = (*p_.outer)(c);
      ++evaluations;
      st.depth_crossing =
          depth_crosses(st.depth.value, r) || open_field_ambiguous(*p_.outer, st.depth, leaf);
      st.depth_layer = layer_of(st.depth.value);
    }
    if (!st.depth_crossing && st.depth_layer < 0) {
      st.uniform = true;
      st.label = 0;
      return st;
    }
    if (parent && parent->inner_state != 2) {
      st.inner_state = parent->inner_state;
    } else if (p_.inner && box_overlaps(c, a, p_.inner->bounds().lo, p_.inner->bounds().hi)) {
      st.inner = (*p_.inner)(c);
      ++evaluations;
      if (std::abs(st.inner.value) < r || open_field_ambiguous(*p_.inner, st.inner, leaf)) {
        st.inner_state = 2;
      } else {
        st.inner_state = st.inner.value >= 0 ? 1 : 0;
      }
    }
    if (st.inner_state == 1) {
      st.uniform = true;
      st.label = 0;
      return st;
    }
    st.body_state.assign(nb, 0);
    st.body_sample.resize(nb);
    bool any_body_crossing = false;
    for (std::size_t b = 0; b < nb; ++b) {
      const auto& body = p_.bodies[b];
      if (parent && !parent->body_state.empty() && parent->body_state[b] != 2) {
        st.body_state[b] = parent->body_state[b];
      } else if (body.box) {
        const Box& bx = *body.box;
        if (box_overlaps(c, a, bx.lo, bx.hi)) {
          const bool inside = c.x - a >= bx.lo.x && c.x + a <= bx.hi.x && c.y - a >= bx.lo.y &&
                              c.y + a <= bx.hi.y && c.z - a >= bx.lo.z && c.z + a <= bx.hi.z;
          st.body_state[b] = inside ? 1 : 2;
        }
      } else if (box_overlaps(c, a, body.field->bounds().lo, body.field->bounds().hi)) {
        st.body_sample[b] = (*body.field)(c);
        ++evaluations;
        const auto& s = st.body_sample[b];
        if (std::abs(s.value) < r || open_field_ambiguous(*body.field, s, leaf)) {
          st.body_state[b] = 2;
        } else {
          st.body_state[b] = s.value >= 0 ? 1 : 0;
        }
      }
      any_body_crossing = any_body_crossing || st.body_state[b] == 2;
    }
    if (!st.depth_crossing && st.inner_state != 2 && !any_body_crossing) {
      st.uniform = true;
      std::vector<char> in(nb);
      for (std::size_t b = 0; b < nb; ++b) in[b] = st.body_state[b] == 1;
      st.label = label_for(st.depth_layer, false, in);
    }
    return st;
  }

  // Adds weight × (fraction of each label in the cell) to acc.
  void integrate(const Vec3d& c, double a, int level, double weight, const CellState& st,
                 std::vector<double>& acc) {
    if (st.uniform) {
      acc[static_cast<std::size_t>(st.label)] += weight;
      return;
    }
    if (level < p_.max_subdivision) {
      const double h = a / 2;
      for (int k = 0; k < 8; ++k) {
        const Vec3d cc{c.x + ((k & 1) ? h : -h), c.y + ((k & 2) ? h : -h),
                       c.z + ((k & 4) ? h : -h)};
        const bool leaf = level + 1 >= p_.max_subdivision;
        integrate(cc, h, level + 1, weight / 8, evaluate(cc, h, leaf, &st), acc);
      }
      return;
    }
    leaf(c, a, weight, st, acc);
  }

  // A crossed leaf: linearised fields; the depth field integrated exactly per sub-cell.
  void leaf(const Vec3d& c, double a, double weight, const CellState& st,
            std::vector<double>& acc) {
    const double r = a * kSqrt3;
    const std::size_t nb = p_.bodies.size();
    // Crossing fields were sampled at this cell; re-decide by distance only (a leaf has no
    // children to resolve a hole's winding number).
    const bool depth_lin = st.depth_crossing && depth_crosses(st.depth.value, r);
    const bool inner_lin = st.inner_state == 2 && std::abs(st.inner.value) < r;
    std::vector<char> body_lin(nb, 0);
    bool others = inner_lin;
    for (std::size_t b = 0; b < nb; ++b) {
      if (st.body_state[b] != 2) continue;
      body_lin[b] = p_.bodies[b].box ? 1 : (std::abs(st.body_sample[b].value) < r ? 1 : 0);
      others = others || body_lin[b];
    }
    // A single crossing mesh field other than depth is integrated exactly too (one plane).
    int exact_other = -2;  // -2 none, -1 inner, b >= 0 body b
    if (!depth_lin) {
      int count = inner_lin ? 1 : 0;
      bool any_box = false;
      for (std::size_t b = 0; b < nb; ++b) {
        if (!body_lin[b]) continue;
        if (p_.bodies[b].box) {
          any_box = true;
        } else {
          ++count;
        }
      }
      if (count == 1 && !any_box) {
        if (inner_lin) {
          exact_other = -1;
        } else {
          for (std::size_t b = 0; b < nb; ++b)
            if (body_lin[b]) exact_other = static_cast<int>(b);
        }
      }
    }
    const int k = (others && exact_other == -2) ? kSubSamples : 1;
    const double s = 2 * a / k;
    const double w_sub = weight / (k * k * k);
    std::vector<char> body_in(nb), bi(nb);
    for (int iz = 0; iz < k; ++iz) {
      for (int iy = 0; iy < k; ++iy) {
        for (int ix = 0; ix < k; ++ix) {
          const Vec3d cc{c.x - a + (ix + 0.5) * s, c.y - a + (iy + 0.5) * s,
                         c.z - a + (iz + 0.5) * s};
          const Vec3d dx = cc - c;
          // States of the sampled fields at the sub-cell centre.
          bool inner_in = st.inner_state == 1;
          if (st.inner_state == 2) {
            inner_in =
                inner_lin ? st.inner.value + dot(st.inner.gradient, dx) >= 0 : st.inner.value >= 0;
          }
          for (std::size_t b = 0; b < nb; ++b) {
            const auto& body = p_.bodies[b];
            if (st.body_state[b] != 2) {
              body_in[b] = st.body_state[b] == 1;
            } else if (body.box) {
              body_in[b] = body.box->contains(cc);
            } else if (body_lin[b]) {
              body_in[b] = st.body_sample[b].value + dot(st.body_sample[b].gradient, dx) >= 0;
            } else {
              body_in[b] = st.body_sample[b].value >= 0;
            }
          }
          int layer = st.depth_layer;
          double depth_c = 0;
          if (st.depth_crossing) {
            depth_c = st.depth.value + dot(st.depth.gradient, dx);
            layer = depth_lin ? layer_of(depth_c) : layer_of(st.depth.value);
          }
          if (depth_lin) {
            // Exact split by depth thresholds: air below 0, layer i below layer_bottoms[i].
            const Vec3d n = s * st.depth.gradient;
            auto below = [&](double t) {
              return cube_fraction_below(n, t - depth_c + 0.5 * (n.x + n.y + n.z));
            };
            double prev = below(0.0);
            acc[0] += w_sub * prev;
            for (int i = 0; i < p_.layer_count; ++i) {
              const double cur = i < static_cast<int>(p_.layer_bottoms.size())
                                     ? below(p_.layer_bottoms[static_cast<std::size_t>(i)])
                                     : 1.0;
              const double f = cur - prev;
              if (f > 0)
                acc[static_cast<std::size_t>(label_for(i, inner_in, body_in))] += w_sub * f;
              prev = std::max(prev, cur);
            }
          } else if (exact_other != -2) {
            const auto& sample = exact_other == -1
                                     ? st.inner
                                     : st.body_sample[static_cast<std::size_t>(exact_other)];
            const Vec3d n = s * sample.gradient;
            // Fraction with value < 0, i.e. outside that mesh.
            const double out = cube_fraction_below(n, -sample.value + 0.5 * (n.x + n.y + n.z));
            for (int side = 0; side < 2; ++side) {
              const double f = side == 0 ? out : 1.0 - out;
              if (f <= 0) continue;
              bi = body_in;
              bool ii = inner_in;
              if (exact_other == -1) {
                ii = side == 1;
              } else {
                bi[static_cast<std::size_t>(exact_other)] = side == 1;
              }
              acc[static_cast<std::size_t>(label_for(layer, ii, bi))] += w_sub * f;
            }
          } else {
            acc[static_cast<std::size_t>(label_for(layer, inner_in, body_in))] += w_sub;
          }
        }
      }
    }
  }

 private:
  const FractionProblem& p_;
};

struct BlockResult {
  std::vector<formats::Lattice> voxels;
  std::vector<std::int64_t> offsets{0};
  std::vector<std::int32_t> labels;
  std::vector<double> fractions;
};

void emit(BlockResult& out, const formats::Lattice& v, const std::vector<double>& acc,
          double min_tissue) {
  double tissue = 0;
  for (std::size_t l = 1; l < acc.size(); ++l) tissue += acc[l];
  if (tissue <= std::max(min_tissue, 1e-12)) return;
  out.voxels.push_back(v);
  for (std::size_t l = 1; l < acc.size(); ++l) {
    if (acc[l] > 1e-12) {
      out.labels.push_back(static_cast<std::int32_t>(l));
      out.fractions.push_back(std::min(acc[l], 1.0));
    }
  }
  out.offsets.push_back(static_cast<std::int64_t>(out.labels.size()));
}

}  // namespace

VoxelFractions compute_fractions(const FractionProblem& p,
                                 const std::function<void(std::int64_t, std::int64_t)>& progress) {
  const auto& g = p.grid;
  const double h = g.voxel_size;
  const std::array<int, 3> nblocks = {(g.dims[0] + kBlock - 1) / kBlock,
                                      (g.dims[1] + kBlock - 1) / kBlock,
                                      (g.dims[2] + kBlock - 1) / kBlock};
  const std::int64_t total =
      static_cast<std::int64_t>(nblocks[0]) * nblocks[1] * static_cast<std::int64_t>(nblocks[2]);
  std::vector<BlockResult> results(static_cast<std::size_t>(total));
  std::atomic<std::int64_t> done{0};
  std::atomic<std::int64_t> evaluations{0};
  auto centre_of = [&](int i, int j, int k, int n) {
    return Vec3d{g.origin[0] + h * (i + 0.5 * n), g.origin[1] + h * (j + 0.5 * n),
                 g.origin[2] + h * (k + 0.5 * n)};
  };

#pragma omp parallel
  {
    Integrator integ(p);
    std::vector<double> acc(static_cast<std::size_t>(p.label_count));
    // Recursive block classification: uniform blocks are filled without per-voxel queries.
    std::function<void(int, int, int, int, BlockResult&, const CellState*)> block =
        [&](int i0, int j0, int k0, int n, BlockResult& out, const CellState* parent) {
          if (i0 >= g.dims[0] || j0 >= g.dims[1] || k0 >= g.dims[2]) return;
          const bool voxel = n == 1;
          const CellState st = integ.evaluate(centre_of(i0, j0, k0, n), 0.5 * n * h,
                                              voxel && p.max_subdivision == 0, parent);
          if (voxel) {
            std::fill(acc.begin(), acc.end(), 0.0);
            integ.integrate(centre_of(i0, j0, k0, 1), 0.5 * h, 0, 1.0, st, acc);
            emit(out, {i0, j0, k0}, acc, p.min_tissue_fraction);
            return;
          }
          if (st.uniform) {
            if (st.label == 0) return;
            std::fill(acc.begin(), acc.end(), 0.0);
            acc[static_cast<std::size_t>(st.label)] = 1.0;
            // Children in lattice order are emitted by the caller's sort; order here is (k, j, i).
            for (int k = k0; k < std::min(k0 + n, g.dims[2]); ++k)
              for (int j = j0; j < std::min(j0 + n, g.dims[1]); ++j)
                for (int i = i0; i < std::min(i0 + n, g.dims[0]); ++i) emit(out, {i, j, k}, acc, 0);
            return;
          }
          const int m = n / 2;
          for (int c = 0; c < 8; ++c) {
            block(i0 + ((c & 1) ? m : 0), j0 + ((c & 2) ? m : 0), k0 + ((c & 4) ? m : 0), m, out,
                  &st);
          }
        };
#pragma omp for schedule(dynamic, 1)
    for (std::int64_t b = 0; b < total; ++b) {
      const int bi = static_cast<int>(b % nblocks[0]);
      const int bj = static_cast<int>((b / nblocks[0]) % nblocks[1]);
      const int bk = static_cast<int>(b / (static_cast<std::int64_t>(nblocks[0]) * nblocks[1]));
      block(bi * kBlock, bj * kBlock, bk * kBlock, kBlock, results[static_cast<std::size_t>(b)],
            nullptr);
      const auto d = ++done;
      if (progress && omp_get_thread_num() == 0) progress(d, total);
    }
    evaluations += integ.evaluations;
  }
  if (progress) progress(total, total);

  // Gather and sort by lattice order (k, j, i); each voxel appears once.
  std::size_t nv = 0, nk = 0;
  for (const auto& r : results) {
    nv += r.voxels.size();
    nk += r.labels.size();
  }
  struct Ref {
    formats::Lattice v;
    std::uint32_t block;
    std::uint32_t index;
  };
  std::vector<Ref> refs;
  refs.reserve(nv);
  for (std::size_t b = 0; b < results.size(); ++b) {
    for (std::size_t i = 0; i < results[b].voxels.size(); ++i) {
      refs.push_back(
          {results[b].voxels[i], static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(i)});
    }
  }
  std::sort(refs.begin(), refs.end(), [](const Ref& x, const Ref& y) {
    if (x.v[2] != y.v[2]) return x.v[2] < y.v[2];
    if (x.v[1] != y.v[1]) return x.v[1] < y.v[1];
    return x.v[0] < y.v[0];
  });
  VoxelFractions out;
  out.voxels.reserve(nv);
  out.offsets.reserve(nv + 1);
  out.labels.reserve(nk);
  out.fractions.reserve(nk);
  for (const auto& ref : refs) {
    const auto& r = results[ref.block];
    out.voxels.push_back(ref.v);
    for (auto q = r.offsets[ref.index]; q < r.offsets[ref.index + 1]; ++q) {
      out.labels.push_back(r.labels[static_cast<std::size_t>(q)]);
      out.fractions.push_back(r.fractions[static_cast<std::size_t>(q)]);
    }
    out.offsets.push_back(static_cast<std::int64_t>(out.labels.size()));
  }
  out.field_evaluations = evaluations.load();
  return out;
}

Vec3d voxel_centre(const formats::VoxelGrid& g, const formats::Lattice& l) {
  const double h = g.voxel_size;
  return {g.origin[0] + h * (l[0] + 0.5), g.origin[1] + h * (l[1] + 0.5),
          g.origin[2] + h * (l[2] + 0.5)};
}

std::int64_t drop_voxels(VoxelFractions& f, const formats::VoxelGrid& grid,
                         const std::function<bool(const Vec3d&)>& drop) {
  VoxelFractions out;
  out.field_evaluations = f.field_evaluations;
  for (std::size_t v = 0; v < f.voxels.size(); ++v) {
    if (drop(voxel_centre(grid, f.voxels[v]))) continue;
    out.voxels.push_back(f.voxels[v]);
    for (auto q = f.offsets[v]; q < f.offsets[v + 1]; ++q) {
      out.labels.push_back(f.labels[static_cast<std::size_t>(q)]);
      out.fractions.push_back(f.fractions[static_cast<std::size_t>(q)]);
    }
    out.offsets.push_back(static_cast<std::int64_t>(out.labels.size()));
  }
  const auto dropped = static_cast<std::int64_t>(f.voxels.size() - out.voxels.size());
  f = std::move(out);
  return dropped;
}

}  // namespace sinew::voxelizer
