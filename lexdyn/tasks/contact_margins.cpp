#include "lexdyn/tasks/contact_margins.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "lexdyn/common/format.hpp"
#include "lexdyn/tasks/task.hpp"

namespace lexdyn::tasks {

namespace {

using V2 = Eigen::Vector2d;

double cross2(const V2& a, const V2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Indices of the convex hull of pts, counter-clockwise (Andrew's monotone chain), collinear
// points left out.
std::vector<int> hull(const std::vector<V2>& pts) {
  std::vector<int> idx(pts.size());
  std::iota(idx.begin(), idx.end(), 0);
  std::sort(idx.begin(), idx.end(),
            [&](int a, int b) { return pts[a].x() < pts[b].x() || (pts[a].x() == pts[b].x() && pts[a].y() < pts[b].y()); });
  std::vector<int> h;
  const double eps = 1e-12;
  for (int pass = 0; pass < 2; ++pass) {
    const size_t start = h.size();
    for (int i : idx) {
      while (h.size() >= start + 2 && cross2(pts[h[h.size() - 1]] - pts[h[h.size() - 2]], pts[i] - pts[h[h.size() - 2]]) <= eps)
        h.pop_back();
      h.push_back(i);
    }
    h.pop_back();
    std::reverse(idx.begin(), idx.end());
  }
  return h;
}

}  // namespace

bool shrinkSupport(std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& normal, double distance, double& room) {
  room = 0.0;
  if (points.size() < 2 || distance <= 0.0) return true;
  const Eigen::Vector3d n = normal.normalized();
  const Eigen::Vector3d a = (std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(n).normalized();
  const Eigen::Vector3d b = n.cross(a);
  std::vector<V2> p2;
  for (const auto& p : points) p2.emplace_back(p.dot(a), p.dot(b));
  const std::vector<int> h = hull(p2);
  std::vector<V2> out = p2;
  if (h.size() < 3) {
    // Collinear (or coincident): the two ends of the segment move toward each other.
    int lo = 0, hi = 0;
    V2 dir = V2::Zero();
    for (size_t i = 1; i < p2.size(); ++i) {
      if ((p2[i] - p2[0]).norm() > dir.norm()) dir = p2[i] - p2[0];
    }
    if (dir.norm() == 0.0) return false;
    dir.normalize();
    for (size_t i = 1; i < p2.size(); ++i) {
      if (p2[i].dot(dir) < p2[lo].dot(dir)) lo = static_cast<int>(i);
      if (p2[i].dot(dir) > p2[hi].dot(dir)) hi = static_cast<int>(i);
    }
    const double len = (p2[hi] - p2[lo]).dot(dir);
    room = len / 2.0;
    if (!(distance < room)) return false;
    const double s0 = p2[lo].dot(dir) + distance, s1 = p2[hi].dot(dir) - distance;
    for (auto& q : out) {
      const double s = std::clamp(q.dot(dir), s0, s1);
      q += (s - q.dot(dir)) * dir;
    }
  } else {
    const size_t m = h.size();
    // Inward unit normals of the edges h[i] -> h[i+1] (counter-clockwise: left of the edge).
    std::vector<V2> en(m);
    std::vector<double> off(m);  // the offset edge: en . x >= off
    for (size_t i = 0; i < m; ++i) {
      const V2 e = p2[h[(i + 1) % m]] - p2[h[i]];
      en[i] = V2(-e.y(), e.x()).normalized();
      off[i] = en[i].dot(p2[h[i]]) + distance;
    }
    // Inradius-like room: the largest distance at which some point is inside every offset edge
    // is at most the smallest distance of the vertex centroid to an edge; the check below is exact.
    V2 c = V2::Zero();
    for (int i : h) c += p2[i];
    c /= static_cast<double>(m);
    room = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < m; ++i) room = std::min(room, en[i].dot(c) - (off[i] - distance));
    std::vector<V2> v(m);
    for (size_t i = 0; i < m; ++i) {
      // Vertex h[i] joins edges i-1 and i: the intersection of their offset lines.
      const V2& n0 = en[(i + m - 1) % m];
      const V2& n1 = en[i];
      v[i] = p2[h[i]] + distance * (n0 + n1) / (1.0 + n0.dot(n1));
    }
    // The offset polygon keeps every edge's direction (no edge vanished or turned over).
    for (size_t i = 0; i < m; ++i) {
      const V2 e0 = p2[h[(i + 1) % m]] - p2[h[i]];
      const V2 e1 = v[(i + 1) % m] - v[i];
      if (!(e1.dot(e0) > 1e-12 * e0.squaredNorm())) return false;
    }
    V2 c1 = V2::Zero();
    for (const V2& q : v) c1 += q;
    c1 /= static_cast<double>(m);
    std::vector<char> is_vertex(p2.size(), 0);
    for (size_t i = 0; i < m; ++i) {
      out[static_cast<size_t>(h[i])] = v[i];
      is_vertex[static_cast<size_t>(h[i])] = 1;
    }
    for (size_t k = 0; k < p2.size(); ++k) {
      if (is_vertex[k]) continue;
      double t = 1.0;  // c1 + t (p - c1) inside every offset edge
      for (size_t i = 0; i < m; ++i) {
        const double inside = en[i].dot(p2[k]) - off[i];
        if (inside < 0.0) t = std::min(t, (en[i].dot(c1) - off[i]) / (en[i].dot(c1) - en[i].dot(p2[k])));
      }
      out[k] = c1 + t * (p2[k] - c1);
    }
  }
  for (size_t k = 0; k < points.size(); ++k) {
    const double h_n = points[k].dot(n);
    points[k] = out[k].x() * a + out[k].y() * b + h_n * n;
  }
  return true;
}

std::vector<std::string> applyContactMargins(ContactSpec& spec, const ContactMargins& m) {
  std::vector<std::string> problems;
  if (!(m.friction >= 0.0 && m.friction < 1.0)) {
    problems.push_back("friction: expected a fraction of the friction coefficient in [0, 1), found " + formatNumber(m.friction));
  }
  if (!(m.cop_m >= 0.0 && std::isfinite(m.cop_m))) problems.push_back("cop_m: expected a distance >= 0 m, found " + formatNumber(m.cop_m));
  if (!(m.min_normal_N >= 0.0 && std::isfinite(m.min_normal_N))) {
    problems.push_back("min_normal_N: expected a force >= 0 N, found " + formatNumber(m.min_normal_N));
  }
  if (!problems.empty() || spec.fixed) return problems;
  if (m.cop_m > 0.0 && !spec.point && spec.points.size() >= 2) {
    double room = 0.0;
    if (!shrinkSupport(spec.points, spec.normal_in_frame, m.cop_m, room)) {
      problems.push_back("cop_m: " + formatNumber(m.cop_m) + " m leaves no support polygon of contact " + spec.name +
                         " (its points allow less than " + formatNumber(room) + " m)");
    }
  }
  spec.friction *= 1.0 - m.friction;
  spec.min_normal_force = m.min_normal_N;
  return problems;
}

}  // namespace lexdyn::tasks
