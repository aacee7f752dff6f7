#include "sinew/voxelizer/winding_number.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "sinew/common/error.hpp"

namespace sinew::voxelizer {
namespace {

constexpr double kInv4Pi = 0.07957747154594767;  // 1 / (4 pi)
constexpr int kLeafSize = 4;  // fewest instructions per query of 4, 8, 16 (callgrind)
// inside(): values within kRefineBand of 1/2 are recomputed at beta = kRefineBeta (error below
// about 3e-4, measured on the Armadillo).
constexpr double kRefineBand = 0.02;
constexpr double kRefineBeta = 4.0;

// Per-node far-field data (Barill et al. 2018, eq. 7-9, here with exact triangle moments).
struct Node {
  Vec3d center;     // area-weighted centroid p
  double radius;    // farthest triangle corner from p
  Vec3d normal;     // N = sum a_t n_t (dipole)
  double c1[3][3];  // C1_ij = sum_t n_i int_t (x - p)_j dA
  // C2_ijk = sum_t n_i int_t (x - p)_j (x - p)_k dA; c2[i] holds the symmetric (j, k) part in
  // Voigt order (xx yy zz yz xz xy).
  double c2[3][6];
  std::int32_t left = -1, right = -1;  // children; -1 for a leaf
  std::int32_t first = 0, count = 0;   // leaf: triangles [first, first + count) in leaf order
};

// What the traversal reads for every node it visits.
struct HotNode {
  Vec3d center;
  double radius2;  // radius^2
  std::int32_t left, right, first, count;
};

// The far field of a node in contracted form, R = p - q:
//   4 pi w ~ N.R/|R|^3 + (tr C1)/|R|^3 - 3 R.S1.R/|R|^5 - 3/2 g.R/|R|^5 + 15/2 P(R)/|R|^7
// with S1 = sym(C1), g_k = 2 sum_i C2_iik + sum_j C2_kjj, and P(R) = sum_ijk C2_ijk R_i R_j R_k
// kept as a cubic polynomial (its 10 monomial coefficients: xxx yyy zzz xxy xxz xyy yyz xzz yzz
// xyz). Expanding the order-2 term T(R):C2/2 gives exactly these contractions.
struct FarField {
  double n[3];
  double tr1;
  double s1[6];  // xx yy zz yz xz xy
  double g[3];
  double p3[10];
};

FarField contract(const Node& node) {
  FarField f{};
  for (int i = 0; i < 3; ++i) f.n[i] = node.normal[i];
  f.tr1 = node.c1[0][0] + node.c1[1][1] + node.c1[2][2];
  f.s1[0] = node.c1[0][0];
  f.s1[1] = node.c1[1][1];
  f.s1[2] = node.c1[2][2];
  f.s1[3] = 0.5 * (node.c1[1][2] + node.c1[2][1]);
  f.s1[4] = 0.5 * (node.c1[0][2] + node.c1[2][0]);
  f.s1[5] = 0.5 * (node.c1[0][1] + node.c1[1][0]);
  // Full C2_ijk from the Voigt storage.
  auto c2 = [&node](int i, int j, int k) {
    const int v = j == k ? j : (j + k == 3 ? 3 : (j + k == 2 ? 4 : 5));
    return node.c2[i][v];
  };
  for (int k = 0; k < 3; ++k) {
    double sum = 0;
    for (int i = 0; i < 3; ++i) sum += c2(i, i, k);
    f.g[k] = 2 * sum + (node.c2[k][0] + node.c2[k][1] + node.c2[k][2]);
  }
  auto monomial = [](int i, int j, int k) {
    int c[3] = {0, 0, 0};
    ++c[i];
    ++c[j];
    ++c[k];
    if (c[0] == 3) return 0;
    if (c[1] == 3) return 1;
    if (c[2] == 3) return 2;
    if (c[0] == 2) return c[1] == 1 ? 3 : 4;
    if (c[1] == 2) return c[0] == 1 ? 5 : 6;
    if (c[2] == 2) return c[0] == 1 ? 7 : 8;
    return 9;
  };
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) f.p3[monomial(i, j, k)] += c2(i, j, k);
  return f;
}

}  // namespace

double triangle_solid_angle(const Vec3d& a0, const Vec3d& b0, const Vec3d& c0, const Vec3d& q) {
  const Vec3d a = a0 - q, b = b0 - q, c = c0 - q;
  const double la = norm(a), lb = norm(b), lc = norm(c);
  const double det = dot(a, cross(b, c));
  // In the triangle's plane, to rounding (on the triangle included), it contributes nothing, so
  // that a point on a closed surface gets 1/2 rather than atan2's +-2 pi inside the triangle.
  if (std::abs(det) <= 1e-12 * la * lb * lc) return 0.0;
  const double den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
  return 2.0 * std::atan2(det, den);
}

struct WindingNumber::Impl {
  double beta = 2.0;
  std::vector<Node> nodes;  // during construction only
  std::vector<HotNode> hot;
  std::vector<FarField> far;
  std::vector<std::array<double, 9>> corners;  // triangles in leaf order: a, b, c

  double exact_range(std::int32_t first, std::int32_t count, const Vec3d& q) const {
    double sum = 0;
    for (std::int32_t t = first; t < first + count; ++t) {
      const auto& c = corners[t];
      sum += triangle_solid_angle({c[0], c[1], c[2]}, {c[3], c[4], c[5]}, {c[6], c[7], c[8]}, q);
    }
    return sum * kInv4Pi;
  }

  static double far_field(const FarField& f, const Vec3d& r) {
    const double r2 = squared_norm(r);
    const double inv = 1.0 / std::sqrt(r2);
    const double inv2 = inv * inv;
    const double inv3 = inv2 * inv, inv5 = inv3 * inv2, inv7 = inv5 * inv2;
    const double x = r.x, y = r.y, z = r.z;
    // order 0 (dipole) and 1: grad G(R).N + H(R):C1, H = I/|R|^3 - 3 R R^T/|R|^5
    const double w01 = (f.n[0] * x + f.n[1] * y + f.n[2] * z + f.tr1) * inv3;
    const double rsr = f.s1[0] * x * x + f.s1[1] * y * y + f.s1[2] * z * z +
                       2 * (f.s1[3] * y * z + f.s1[4] * x * z + f.s1[5] * x * y);
    // order 2: 1/2 T(R):C2, T_ijk = -3 (d_ij R_k + d_ik R_j + d_jk R_i)/|R|^5 + 15 R_i R_j
    // R_k/|R|^7
    const double gr = f.g[0] * x + f.g[1] * y + f.g[2] * z;
    const double p = f.p3[0] * x * x * x + f.p3[1] * y * y * y + f.p3[2] * z * z * z +
                     x * (f.p3[3] * x * y + f.p3[4] * x * z + f.p3[5] * y * y) +
                     z * (f.p3[6] * y * y + f.p3[7] * x * z + f.p3[8] * y * z) +
                     f.p3[9] * x * y * z;
    return (w01 - (3.0 * rsr + 1.5 * gr) * inv5 + 7.5 * p * inv7) * kInv4Pi;
  }

  double evaluate(const Vec3d& q) const { return evaluate(q, beta); }

  // w(q) for classification: near 1/2, where the far-field error (up to about 1e-2 at beta = 2)
  // could flip the answer, evaluated again with a wider near field.
  bool inside(const Vec3d& q) const {
    const double w = evaluate(q, beta);
    if (std::abs(w - 0.5) > kRefineBand) return w >= 0.5;
    return evaluate(q, std::max(kRefineBeta, beta)) >= 0.5;
  }

  double evaluate(const Vec3d& q, double accuracy_beta) const {
    double sum = 0;
    std::int32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    const double beta2 = accuracy_beta * accuracy_beta;
    while (top > 0) {
      const std::int32_t id = stack[--top];
      const HotNode& n = hot[id];
      const Vec3d r = n.center - q;
      if (squared_norm(r) > beta2 * n.radius2) {
        sum += far_field(far[id], r);
      } else if (n.left < 0) {
        sum += exact_range(n.first, n.count, q);
      } else {
        stack[top++] = n.right;
        stack[top++] = n.left;
      }
    }
    return sum;
  }
  // Builds the node for leaf-ordered triangles [first, first + count) of order, recursively.
  std::int32_t build(const TriangleMesh& m, std::vector<std::int32_t>& order,
                     const std::vector<Vec3d>& centroid, std::int32_t first, std::int32_t count,
                     int depth) {
    const auto id = static_cast<std::int32_t>(nodes.size());
    nodes.emplace_back();
    if (count <= kLeafSize || depth >= 100) {
      nodes[id].first = first;
      nodes[id].count = count;
    } else {
      Vec3d lo = centroid[order[first]], hi = lo;
      for (std::int32_t k = first; k < first + count; ++k) {
        const Vec3d& c = centroid[order[k]];
        lo = {std::min(lo.x, c.x), std::min(lo.y, c.y), std::min(lo.z, c.z)};
        hi = {std::max(hi.x, c.x), std::max(hi.y, c.y), std::max(hi.z, c.z)};
      }
      const Vec3d ext = hi - lo;
      const int axis = ext.x >= ext.y ? (ext.x >= ext.z ? 0 : 2) : (ext.y >= ext.z ? 1 : 2);
      const std::int32_t half = count / 2;
      // Ties broken by index so that the tree does not depend on the library's nth_element.
      std::nth_element(order.begin() + first, order.begin() + first + half,
                       order.begin() + first + count, [&](std::int32_t a, std::int32_t b) {
                         const double ca = centroid[a][axis], cb = centroid[b][axis];
                         return ca != cb ? ca < cb : a < b;
                       });
      const std::int32_t l = build(m, order, centroid, first, half, depth + 1);
      const std::int32_t r = build(m, order, centroid, first + half, count - half, depth + 1);
      nodes[id].left = l;
      nodes[id].right = r;
      nodes[id].first = first;
      nodes[id].count = count;
    }
    // Expansion data over all triangles below this node.
    Node& n = nodes[id];
    double area = 0;
    Vec3d p{0, 0, 0}, normal{0, 0, 0};
    for (std::int32_t k = first; k < first + count; ++k) {
      const auto& t = m.triangles[order[k]];
      const Vec3d a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
      const Vec3d an = 0.5 * cross(b - a, c - a);  // area times unit normal
      const double ak = norm(an);
      area += ak;
      p += ak * centroid[order[k]];
      normal += an;
    }
    if (area > 0) {
      p = (1.0 / area) * p;
    } else {
      p = {0, 0, 0};
      for (std::int32_t k = first; k < first + count; ++k) p += centroid[order[k]];
      p = (1.0 / count) * p;
    }
    n.center = p;
    n.normal = normal;
    n.radius = 0;
    for (auto& row : n.c1) std::fill(row, row + 3, 0.0);
    for (auto& row : n.c2) std::fill(row, row + 6, 0.0);
    for (std::int32_t k = first; k < first + count; ++k) {
      const auto& t = m.triangles[order[k]];
      const Vec3d x[3] = {m.vertices[t[0]] - p, m.vertices[t[1]] - p, m.vertices[t[2]] - p};
      const Vec3d an = 0.5 * cross(x[1] - x[0], x[2] - x[0]);
      for (const Vec3d& xi : x) n.radius = std::max(n.radius, norm(xi));
      // int_t d dA = a * centroid; int_t d d^T dA = a/12 (sum x_i x_i^T + s s^T), s = sum x_i.
      const Vec3d s = x[0] + x[1] + x[2];
      const Vec3d mean = (1.0 / 3.0) * s;
      double mom[6];
      const int vi[6] = {0, 1, 2, 1, 0, 0}, vj[6] = {0, 1, 2, 2, 2, 1};
      for (int v = 0; v < 6; ++v) {
        double acc = s[vi[v]] * s[vj[v]];
        for (const Vec3d& xi : x) acc += xi[vi[v]] * xi[vj[v]];
        mom[v] = acc / 12.0;  // times |an| below; an = a * unit normal
      }
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) n.c1[i][j] += an[i] * mean[j];
        for (int v = 0; v < 6; ++v) n.c2[i][v] += an[i] * mom[v];
      }
    }
    return id;
  }
};

WindingNumber::WindingNumber(const TriangleMesh& mesh, double accuracy_beta)
    : impl_(std::make_unique<Impl>()) {
  if (mesh.triangles.empty())
    throw GeometryError(mesh.source, "triangles", "winding number of a mesh without triangles");
  if (!(accuracy_beta > 1.0))
    throw GeometryError(mesh.source, "accuracy_beta", "must be greater than 1");
  check_triangle_indices(mesh);
  impl_->beta = accuracy_beta;
  const auto nt = static_cast<std::int32_t>(mesh.triangles.size());
  std::vector<Vec3d> centroid(static_cast<std::size_t>(nt));
  for (std::int32_t i = 0; i < nt; ++i) {
    const auto& t = mesh.triangles[i];
    centroid[i] = (1.0 / 3.0) * (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]);
  }
  std::vector<std::int32_t> order(static_cast<std::size_t>(nt));
  std::iota(order.begin(), order.end(), 0);
  impl_->nodes.reserve(static_cast<std::size_t>(4 * nt / kLeafSize + 8));
  impl_->build(mesh, order, centroid, 0, nt, 0);
  impl_->hot.reserve(impl_->nodes.size());
  impl_->far.reserve(impl_->nodes.size());
  for (const Node& n : impl_->nodes) {
    impl_->hot.push_back({n.center, n.radius * n.radius, n.left, n.right, n.first, n.count});
    impl_->far.push_back(contract(n));
  }
  impl_->nodes = {};
  impl_->corners.resize(static_cast<std::size_t>(nt));
  for (std::int32_t k = 0; k < nt; ++k) {
    const auto& t = mesh.triangles[order[k]];
    auto& c = impl_->corners[k];
    for (int v = 0; v < 3; ++v) {
      const Vec3d& x = mesh.vertices[t[v]];
      c[3 * v] = x.x;
      c[3 * v + 1] = x.y;
      c[3 * v + 2] = x.z;
    }
  }
}

WindingNumber::~WindingNumber() = default;
WindingNumber::WindingNumber(WindingNumber&&) noexcept = default;
WindingNumber& WindingNumber::operator=(WindingNumber&&) noexcept = default;

double WindingNumber::operator()(const Vec3d& p) const {
  return impl_->evaluate(p);
}

bool WindingNumber::inside(const Vec3d& p) const {
  return impl_->inside(p);
}

void WindingNumber::classify(const std::vector<Vec3d>& points,
                             std::vector<std::uint8_t>& out) const {
  out.resize(points.size());
  const auto n = static_cast<std::int64_t>(points.size());
  const Impl& impl = *impl_;
#pragma omp parallel for schedule(dynamic, 256)
  for (std::int64_t i = 0; i < n; ++i) out[i] = impl.inside(points[i]) ? 1 : 0;
}

void WindingNumber::evaluate(const std::vector<Vec3d>& points, std::vector<double>& out) const {
  out.resize(points.size());
  const auto n = static_cast<std::int64_t>(points.size());
  const Impl& impl = *impl_;
#pragma omp parallel for schedule(dynamic, 256)
  for (std::int64_t i = 0; i < n; ++i) out[i] = impl.evaluate(points[i]);
}

double WindingNumber::exact(const Vec3d& p) const {
  return impl_->exact_range(0, static_cast<std::int32_t>(impl_->corners.size()), p);
}

double WindingNumber::accuracy_beta() const {
  return impl_->beta;
}
std::int64_t WindingNumber::triangle_count() const {
  return static_cast<std::int64_t>(impl_->corners.size());
}
std::int64_t WindingNumber::node_count() const {
  return static_cast<std::int64_t>(impl_->hot.size());
}

}  // namespace sinew::voxelizer
