#include "sinew/voxelizer/jaw.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <utility>

#include "sinew/common/error.hpp"
#include "sinew/voxelizer/face_frame.hpp"

namespace sinew::voxelizer {

JawGeometry jaw_geometry(const Landmarks& l) {
  const FaceFrame f = face_frame(l);
  const auto fail = [&](const std::string& landmark, const std::string& problem) {
    throw ConfigError(l.file.string(), "landmarks." + landmark,
                      "cannot make a mandible: " + problem);
  };
  JawGeometry j;
  j.axis = f.lat(true);
  j.forward = f.fwd;
  j.up = f.up;
  const Vec3d tl = l.at("tragus_left"), tr = l.at("tragus_right");
  j.pivot = 0.5 * (tl + tr) + kCondyleAheadOfTragus * j.forward;
  j.half_condyles = 0.5 * std::abs(dot(tl - tr, j.axis));
  const Vec3d upper = l.at("upper_lip"), lower = l.at("lower_lip");
  if (!(dot(upper - lower, j.up) > 0))
    fail("lower_lip", "the lower lip is not below the upper lip along the face's up");
  j.stomion = 0.5 * (upper + lower);
  if (!(dot(j.stomion - j.pivot, j.up) < -0.02))
    fail("upper_lip", "the lips are not at least 20 mm below the tragi");
  if (!(dot(j.stomion - j.pivot, j.forward) > 0.03))
    fail("upper_lip", "the lips are not at least 30 mm in front of the jaw's axis");
  j.incisal = j.stomion - kLipDepth * j.forward;
  const Vec3d cl = l.at("mouth_corner_left"), cr = l.at("mouth_corner_right");
  const double left = dot(cl - j.stomion, j.axis), right = dot(cr - j.stomion, j.axis);
  if (!(left > 0.005 && right < -0.005))
    fail("mouth_corner_left", "the mouth's corners are not either side of the lips' middle");
  j.half_mouth = 0.5 * (left - right);
  if (j.half_mouth > j.half_condyles)
    fail("mouth_corner_left", "the mouth is wider than the distance between the tragi");
  // The arch: k · lateral² behind the incisal point, reaching the corners' depth minus the lips'.
  const double corner_depth =
      0.5 * (dot(cl - j.stomion, j.forward) + dot(cr - j.stomion, j.forward));  // ≤ 0
  j.arch_curvature = std::max(0.0, -corner_depth) / (j.half_mouth * j.half_mouth);
  return j;
}

bool in_mandible(const JawGeometry& j, const Vec3d& p) {
  return dot(p - j.stomion, j.up) < 0 && dot(p - j.pivot, j.forward) > -kMandibleBehindPivot &&
         std::abs(dot(p - j.pivot, j.axis)) <= j.half_condyles;
}

bool near_occlusal_plane(const JawGeometry& j, const Vec3d& c, double h) {
  return std::abs(dot(c - j.stomion, j.up)) <= 0.5 * h && dot(c - j.pivot, j.forward) > 0 &&
         std::abs(dot(c - j.pivot, j.axis)) <= j.half_condyles;
}

bool in_jaw_cut(const JawGeometry& j, const Vec3d& c, double h, double skull_depth,
                double skin_depth) {
  if (!near_occlusal_plane(j, c, h)) return false;
  const double lateral = dot(c - j.stomion, j.axis);
  const double arch = dot(j.incisal - j.stomion, j.forward) - j.arch_curvature * lateral * lateral;
  if (std::abs(lateral) <= j.half_mouth && dot(c - j.stomion, j.forward) >= arch)
    return true;  // between the lips
  // The vestibule along the teeth: next to the bone, under the cheek's skin.
  return dot(c - j.incisal, j.forward) >= -kArchDepth && skull_depth > -kVestibuleVoxels * h &&
         skin_depth >= kVestibuleVoxels * h;
}

std::vector<std::array<formats::Index, 2>> lip_pairs(
    const JawGeometry& jaw, const formats::Model& model,
    const std::vector<std::array<std::int32_t, 3>>& cut, const std::vector<formats::Index>& held) {
  // The lattice axis a nearest up, the other two b and c; s: whether up points along +a.
  int a = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(jaw.up[k]) > std::abs(jaw.up[a])) a = k;
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  const bool s = jaw.up[a] > 0;
  std::map<std::array<std::int32_t, 3>, formats::Index> node_at;
  for (std::size_t n = 0; n < model.node_lattice.size(); ++n)
    node_at.emplace(model.node_lattice[n], static_cast<formats::Index>(n));
  const auto find = [&](std::int32_t ia, std::int32_t ib, std::int32_t ic) -> formats::Index {
    std::array<std::int32_t, 3> l{};
    l[a] = ia;
    l[b] = ib;
    l[c] = ic;
    const auto it = node_at.find(l);
    return it == node_at.end() ? -1 : it->second;
  };
  // The removed voxels by column (b, c), their a coordinates sorted.
  std::map<std::pair<std::int32_t, std::int32_t>, std::vector<std::int32_t>> columns;
  for (const auto& v : cut) columns[{v[b], v[c]}].push_back(v[a]);
  std::vector<std::tuple<std::int32_t, formats::Index, formats::Index>> candidates;  // gap, up, low
  for (auto& [bc, as] : columns) {
    std::sort(as.begin(), as.end());
    for (std::size_t i = 0; i < as.size();) {
      std::size_t j = i;
      while (j + 1 < as.size() && as[j + 1] == as[j] + 1) ++j;
      const std::int32_t bottom = as[i], top = as[j] + 1;  // node layers below and above the run
      for (int db = 0; db < 2; ++db) {
        for (int dc = 0; dc < 2; ++dc) {
          const formats::Index lo = find(bottom, bc.first + db, bc.second + dc);
          const formats::Index hi = find(top, bc.first + db, bc.second + dc);
          if (lo < 0 || hi < 0) continue;
          if (s)
            candidates.emplace_back(top - bottom, hi, lo);
          else
            candidates.emplace_back(top - bottom, lo, hi);
        }
      }
      i = j + 1;
    }
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  const auto is_held = [&](formats::Index n) {
    return std::binary_search(held.begin(), held.end(), n);
  };
  std::vector<char> used(model.node_lattice.size(), 0);
  std::vector<std::array<formats::Index, 2>> pairs;
  for (const auto& [gap, upper, lower] : candidates) {
    (void)gap;
    const auto u = static_cast<std::size_t>(upper), l = static_cast<std::size_t>(lower);
    if (used[u] || used[l] || (is_held(upper) && is_held(lower))) continue;
    used[u] = used[l] = 1;
    pairs.push_back({upper, lower});
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace sinew::voxelizer
