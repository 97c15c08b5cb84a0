#include "harness/robot/robot_layout.hpp"

#include "harness/robot/mesh.hpp"
#include "lexdyn/common/error.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/model/robot_model.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <numeric>

namespace lexdyn::robot {

namespace {

constexpr double kPi = 3.14159265358979323846;
/// The band above a foot's lowest point whose points make its sole (m).
constexpr double kSoleBand_m = 0.003;
/// A foot whose sole points span less than this is a point foot (m).
constexpr double kPointFootSpan_m = 0.02;
/// The band is widened (a rounded or tilted sole) only for a foot this wide within 1 cm (m).
constexpr double kSoleSpan_m = 0.05;
/// A foot this far above the lowest one is in the air (m).
constexpr double kFootInAir_m = 0.002;

// Points of one geometry that bound it (world): box corners, sphere extremes along the world
// axes, cylinder rims (with the exact lowest points of a tilted cylinder), mesh vertices.
void geometryPoints(const model::GeometryDescription& g, const Eigen::Isometry3d& X_world_body, bool apply_up_axis, MeshCache& meshes,
                    ProblemList& problems, std::vector<Eigen::Vector3d>& out) {
  const Eigen::Isometry3d X = X_world_body * g.placement;
  switch (g.type) {
    case model::GeometryType::Box:
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d s((k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5);
        out.push_back(X * s.cwiseProduct(g.size));
      }
      break;
    case model::GeometryType::Sphere:
      for (int a = 0; a < 3; ++a) {
        for (double sgn : {-1.0, 1.0}) out.push_back(X.translation() + sgn * g.radius * Eigen::Vector3d::Unit(a));
      }
      break;
    case model::GeometryType::Cylinder: {
      const Eigen::Vector3d axis = X.linear().col(2);
      Eigen::Vector3d down = -Eigen::Vector3d::UnitZ() + axis.z() * axis;  // -z without its axial part
      for (double end : {-0.5, 0.5}) {
        const Eigen::Vector3d c = X * Eigen::Vector3d(0, 0, end * g.length);
        for (int k = 0; k < 16; ++k) {
          const double t = 2.0 * kPi * k / 16.0;
          out.push_back(c + g.radius * (X.linear() * Eigen::Vector3d(std::cos(t), std::sin(t), 0.0)));
        }
        if (down.norm() > 1e-9) out.push_back(c + g.radius * down.normalized());
      }
      break;
    }
    case model::GeometryType::Mesh: {
      if (g.mesh_path.empty()) return;
      const Mesh* m = nullptr;
      problems.attempt([&] { m = &meshes.get(g.mesh_path); });
      if (!m) {
        meshes.meshes[g.mesh_path] = Mesh{};  // unreadable: said once, then no points
        return;
      }
      // The file's coordinates turned to z up (when asked), then URDF's scale, then the placement.
      const Eigen::Matrix3d R = upAxisRotation(apply_up_axis ? m->up_axis : 'Z').cast<double>();
      const Eigen::Matrix3d A = X.linear() * g.scale.asDiagonal() * R;
      const Eigen::Vector3d t = X.translation();
      out.reserve(out.size() + m->vertices.size());
      for (const auto& v : m->vertices) out.push_back(A * v.cast<double>() + t);
      break;
    }
  }
}

// +1 when a name says left (left_..., l_..., ..._l_..., LLEG, LHip), -1 right, 0 neither.
// `leg_letters`: a robot on three or more feet, whose two-letter leg names (FL_, RL_) are read
// before the capital-letter rule (on a humanoid RL_ is the right leg).
int sideOfName(const std::string& name, bool leg_letters) {
  std::vector<std::string> tokens;
  std::string cur;
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    if (c == '_' || c == '-' || c == '/' || c == '.') {
      if (!cur.empty()) tokens.push_back(cur);
      cur.clear();
      continue;
    }
    cur += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  if (!cur.empty()) tokens.push_back(cur);
  for (const auto& t : tokens) {
    if (t == "left" || t == "l" || t.rfind("left", 0) == 0) return 1;
    if (t == "right" || t == "r" || t.rfind("right", 0) == 0) return -1;
  }
  // Legged robots' two-letter leg names: FL_, RR_ (Unitree: front / rear), LF_, RH_ (ANYmal:
  // front / hind), lm_ (hexapods: middle), fl_, hr_: a side letter with a position letter, or two
  // side letters (RL_: rear left, lr_: left rear, rr_: right); an l makes it left.
  for (const auto& t : tokens) {
    if (!leg_letters) break;
    if (t.size() != 2 || t.find_first_not_of("fhbmlr") != std::string::npos || t.find_first_of("lr") == std::string::npos) continue;
    return t.find('l') != std::string::npos ? 1 : -1;
  }
  // LLEG_JOINT0, LHipPitch, RArm: a capital L or R followed by another capital letter.
  if (name.size() >= 2 && std::isupper(static_cast<unsigned char>(name[1]))) {
    if (name[0] == 'L') return 1;
    if (name[0] == 'R') return -1;
  }
  return 0;
}

// Distance along a kinematic chain: the sum of the distances between consecutive points.
double chainLength(const std::vector<Eigen::Vector3d>& pts) {
  double L = 0.0;
  for (size_t k = 1; k < pts.size(); ++k) L += (pts[k] - pts[k - 1]).norm();
  return L;
}

}  // namespace

std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(),
            [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  p.erase(std::unique(p.begin(), p.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return (a - b).norm() < 1e-9; }),
          p.end());
  if (p.size() < 3) return p;
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> h(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 1e-12) --k;
    h[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 1e-12) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

double marginInPolygon(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p) {
  if (poly.size() < 3) {
    double d = std::numeric_limits<double>::infinity();
    for (const auto& q : poly) d = std::min(d, (q - p).norm());
    if (poly.size() == 2) {
      const Eigen::Vector2d a = poly[0], b = poly[1];
      const double t = std::clamp((p - a).dot(b - a) / std::max((b - a).squaredNorm(), 1e-18), 0.0, 1.0);
      d = (a + t * (b - a) - p).norm();
    }
    return -d;
  }
  double m = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < poly.size(); ++i) {
    const Eigen::Vector2d a = poly[i], b = poly[(i + 1) % poly.size()];
    const Eigen::Vector2d e = (b - a).normalized();
    const double inside = e.x() * (p.y() - a.y()) - e.y() * (p.x() - a.x());  // > 0 left of a->b (inside for CCW)
    m = std::min(m, inside);
  }
  return m;
}

std::vector<Eigen::Vector2d> supportPolygon(const RobotLayout& layout) {
  std::vector<Eigen::Vector2d> pts;
  for (const auto& f : layout.feet) {
    for (const auto& p : f.points_world) pts.emplace_back(p.x(), p.y());
  }
  return convexHull(pts);
}

RobotLayout analyseLayout(const model::RobotDescription& d, const Eigen::VectorXd& posture, ProblemList& problems, MeshCache* cache) {
  RobotLayout L;
  L.posture = posture;
  const model::RobotModel model(d);
  model::ModelData data = model.createData();
  model::Configuration q = model.neutralConfiguration();
  q.joints = posture;
  model.update(data, q, Eigen::VectorXd::Zero(model.nv()));
  const int nb = model.numBodies();
  for (int b = 0; b < nb; ++b) L.body_pose.push_back(model.bodyPlacement(data, b));
  L.com = model.centerOfMass(data);
  L.mass = model.totalMass();

  // Bounding points of every body: collision geometry, else visual, else its origin and CoM.
  MeshCache own;
  MeshCache& meshes = cache ? *cache : own;
  for (const auto& g : d.geometries) {
    L.geometry_points.emplace_back();
    geometryPoints(g, L.body_pose[static_cast<size_t>(g.link)], d.mesh_up_axis_from_file, meshes, problems, L.geometry_points.back());
  }
  std::vector<std::vector<Eigen::Vector3d>> pts(static_cast<size_t>(nb));
  std::vector<std::string> shapes(static_cast<size_t>(nb));
  for (int b = 0; b < nb; ++b) {
    for (bool collision : {true, false}) {
      for (size_t gi = 0; gi < d.geometries.size(); ++gi) {
        const auto& g = d.geometries[gi];
        if (g.link != b || g.collision != collision) continue;
        pts[static_cast<size_t>(b)].insert(pts[static_cast<size_t>(b)].end(), L.geometry_points[gi].begin(), L.geometry_points[gi].end());
        const char* kind[] = {"box", "sphere", "cylinder", "mesh"};
        std::string s =
            std::string(collision ? "collision " : "visual ") + kind[static_cast<int>(g.type)] + " of link '" + g.urdf_link + "'";
        if (shapes[static_cast<size_t>(b)].find(s) == std::string::npos)
          shapes[static_cast<size_t>(b)] += (shapes[static_cast<size_t>(b)].empty() ? "" : ", ") + s;
      }
      if (!pts[static_cast<size_t>(b)].empty()) break;
    }
    if (pts[static_cast<size_t>(b)].empty()) {
      pts[static_cast<size_t>(b)].push_back(L.body_pose[static_cast<size_t>(b)].translation());
      pts[static_cast<size_t>(b)].push_back(L.body_pose[static_cast<size_t>(b)] * d.links[static_cast<size_t>(b)].com);
      shapes[static_cast<size_t>(b)] = "no geometry: the body's origin and centre of mass";
    }
  }
  std::vector<double> low(static_cast<size_t>(nb)), high(static_cast<size_t>(nb));
  // Each body's lowest and highest point, and the robot's (again after the robot is turned).
  auto measureHeights = [&] {
    for (int b = 0; b < nb; ++b) {
      low[static_cast<size_t>(b)] = high[static_cast<size_t>(b)] = pts[static_cast<size_t>(b)][0].z();
      for (const auto& p : pts[static_cast<size_t>(b)]) {
        low[static_cast<size_t>(b)] = std::min(low[static_cast<size_t>(b)], p.z());
        high[static_cast<size_t>(b)] = std::max(high[static_cast<size_t>(b)], p.z());
      }
    }
    L.lowest_z = *std::min_element(low.begin(), low.end());
    L.highest_z = *std::max_element(high.begin(), high.end());
    L.height = L.highest_z - L.lowest_z;
  };
  measureHeights();

  // Tree, subtree masses, and limbs. The trunk is the root and every body that branches into two
  // or more subtrees of significant mass (2 % of the robot), with the bodies between them; a limb
  // starts at each other child of a trunk body and follows its heaviest child down to a leaf
  // (a hand's fingers are side branches of its arm, not limbs of their own).
  std::vector<int> parent(static_cast<size_t>(nb), -1);
  std::vector<std::vector<int>> children(static_cast<size_t>(nb));
  for (int b = 1; b < nb; ++b) {
    parent[static_cast<size_t>(b)] = d.parentBody(b);
    children[static_cast<size_t>(parent[static_cast<size_t>(b)])].push_back(b);
  }
  std::vector<double> subtree_mass(static_cast<size_t>(nb), 0.0);
  for (int b = nb - 1; b >= 0; --b) {
    subtree_mass[static_cast<size_t>(b)] += d.links[static_cast<size_t>(b)].mass;
    if (b > 0) subtree_mass[static_cast<size_t>(parent[static_cast<size_t>(b)])] += subtree_mass[static_cast<size_t>(b)];
  }
  const double significant = 0.02 * subtree_mass[0];
  std::vector<bool> trunk(static_cast<size_t>(nb), false);
  for (int b = 0; b < nb; ++b) {
    int heavy = 0;
    for (int c : children[static_cast<size_t>(b)]) heavy += subtree_mass[static_cast<size_t>(c)] >= significant;
    if (b == 0 || heavy >= 2) {
      for (int k = b; k >= 0 && !trunk[static_cast<size_t>(k)]; k = parent[static_cast<size_t>(k)]) trunk[static_cast<size_t>(k)] = true;
    }
  }
  struct Limb {
    std::vector<int> bodies;  // the chain, from the first (nearest the trunk) to the leaf
    std::vector<int> all;     // every body of the limb's subtree
  };
  std::vector<Limb> limbs;
  for (int t = 0; t < nb; ++t) {
    if (!trunk[static_cast<size_t>(t)]) continue;
    for (int first : children[static_cast<size_t>(t)]) {
      if (trunk[static_cast<size_t>(first)]) continue;
      Limb limb;
      for (int c = first; c >= 0;) {
        limb.bodies.push_back(c);
        int next = -1;
        for (int k : children[static_cast<size_t>(c)]) {
          if (next < 0 || subtree_mass[static_cast<size_t>(k)] > subtree_mass[static_cast<size_t>(next)]) next = k;
        }
        c = next;
      }
      std::vector<int> stack{first};
      while (!stack.empty()) {
        const int k = stack.back();
        stack.pop_back();
        limb.all.push_back(k);
        for (int c : children[static_cast<size_t>(k)]) stack.push_back(c);
      }
      limbs.push_back(limb);
    }
  }

  // Feet: per limb, the body nearest the ground when it touches the lowest level of the robot.
  const double tol = std::max(0.01, 0.03 * L.height);
  const bool root_on_ground = low[0] <= L.lowest_z + tol;
  std::vector<int> foot_limb;
  if (d.base == model::BaseType::Fixed) {
    L.base_reason = "the root link is welded to the world (base: fixed)";
  } else {
    for (size_t li = 0; li < limbs.size(); ++li) {
      // The body of the limb that touches the lowest level: the lowest one (ties within 1 mm: the
      // one with the most points at its bottom).
      int best = -1, best_count = -1;
      double best_low = 1e18;
      for (int b : limbs[li].all) best_low = std::min(best_low, low[static_cast<size_t>(b)]);
      if (best_low > L.lowest_z + tol) continue;
      for (int b : limbs[li].all) {
        if (low[static_cast<size_t>(b)] > best_low + 0.001) continue;
        int count = 0;
        for (const auto& p : pts[static_cast<size_t>(b)]) count += p.z() <= low[static_cast<size_t>(b)] + kSoleBand_m;
        if (count > best_count) {
          best = b;
          best_count = count;
        }
      }
      if (best >= 0) {
        FootLayout f;
        f.body = best;
        f.link = d.links[static_cast<size_t>(best)].name;
        L.feet.push_back(f);
        foot_limb.push_back(static_cast<int>(li));
      }
    }
    L.legged = L.feet.size() >= 2 && !root_on_ground;
    if (!L.legged) {
      L.base_reason = root_on_ground ? "its root link '" + d.links[0].name + "' is at the robot's lowest level (a base on the ground)"
                                     : std::to_string(L.feet.size()) + " chain(s) reach the ground (legs need 2 or more)";
      L.feet.clear();
      foot_limb.clear();
    } else {
      L.base_reason = std::to_string(L.feet.size()) + " chains reach the ground below the root link (legs)";
    }
  }

  // Two feet standing flat in the URDF's zero configuration (the convention of humanoid
  // descriptions) may be tilted by a posture whose legs do not cancel (an SRDF's half-sitting
  // with the ankles a little off): the robot stands on them flat with its base tilted, which is
  // what the start's equilibrium finds. The layout turns the whole robot so (up to 15 deg, both
  // feet agreeing within 2 deg).
  if (L.legged && L.feet.size() == 2) {
    model::Configuration q0 = model.neutralConfiguration();
    for (int j = 0; j < model.numJoints(); ++j) {
      q0.joints[j] = std::min(std::max(0.0, model.jointLowerLimits()[j]), model.jointUpperLimits()[j]);
    }
    model::ModelData data0 = model.createData();
    model.update(data0, q0, Eigen::VectorXd::Zero(model.nv()));
    std::vector<Eigen::Vector3d> ups;
    for (const auto& f : L.feet) {
      const Eigen::Matrix3d R0 = model.bodyPlacement(data0, f.body).linear(), Rp = L.body_pose[static_cast<size_t>(f.body)].linear();
      ups.push_back(Rp * R0.transpose() * Eigen::Vector3d::UnitZ());  // the foot's zero-configuration up, in the posture
    }
    const double agree = std::acos(std::clamp(ups[0].dot(ups[1]), -1.0, 1.0));
    const Eigen::Vector3d u = (ups[0] + ups[1]).normalized();
    const double tilt = std::acos(std::clamp(u.z(), -1.0, 1.0));
    if (tilt > 1e-4 && tilt <= 15.0 * kPi / 180.0 && agree <= 2.0 * kPi / 180.0) {
      const Eigen::Matrix3d C = Eigen::Quaterniond::FromTwoVectors(u, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      for (auto& X : L.body_pose) X = Eigen::Isometry3d(C) * X;
      L.base_rotation = C;
      for (auto& g : L.geometry_points) {
        for (auto& p : g) p = C * p;
      }
      for (auto& b : pts) {
        for (auto& p : b) p = C * p;
      }
      L.com = C * L.com;
      measureHeights();
      L.notes.push_back("the posture tilts the feet by " + formatNumber(tilt * 180.0 / kPi, 3) +
                        " deg from their zero-configuration attitude: the robot is turned to stand them flat (the base tilted; the start's "
                        "equilibrium finds the same)");
    }
  }

  // Soles: the foot's points within a band of its lowest point; a point foot when they span less
  // than 2 cm, or when the robot stands on three or more feet whose legs have fewer than 6 joints
  // (a leg of 3 cannot hold a foot's orientation: held as a pose, such feet lock the base); else
  // the extreme points along the foot's diagonals.
  for (auto& f : L.feet) {
    int leg_joints = 0;
    for (int b = f.body; b > 0 && !trunk[static_cast<size_t>(b)]; b = d.parentBody(b)) {
      if (d.links[static_cast<size_t>(b)].parent_joint >= 0) ++leg_joints;
    }
    const bool few_joints = L.feet.size() >= 3 && leg_joints < 6;
    const Eigen::Isometry3d& X = L.body_pose[static_cast<size_t>(f.body)];
    const double zmin = low[static_cast<size_t>(f.body)];
    Eigen::Vector2d heading = X.linear().col(0).head<2>();
    if (heading.norm() < 0.3) heading = Eigen::Vector2d::UnitX();
    heading.normalize();
    const Eigen::Vector2d lateral(-heading.y(), heading.x());
    // The sole: the points within a band above the lowest; a band of 3 mm, widened up to 1 cm
    // when its points make a line (a rounded or slightly tilted sole) while the foot is wider
    // (5 cm or more within 1 cm).
    std::vector<Eigen::Vector3d> sole;
    double band = kSoleBand_m;
    for (; band <= 0.0101; band += 0.001) {
      sole.clear();
      for (const auto& p : pts[static_cast<size_t>(f.body)]) {
        if (p.z() <= zmin + band) sole.push_back(p);
      }
      double w_lo = 1e9, w_hi = -1e9, l_lo = 1e9, l_hi = -1e9;
      for (const auto& p : sole) {
        w_lo = std::min(w_lo, p.head<2>().dot(lateral));
        w_hi = std::max(w_hi, p.head<2>().dot(lateral));
        l_lo = std::min(l_lo, p.head<2>().dot(heading));
        l_hi = std::max(l_hi, p.head<2>().dot(heading));
      }
      // A point or a line while the foot's points within 1 cm are wider: widen the band.
      if (std::min(w_hi - w_lo, l_hi - l_lo) >= kPointFootSpan_m) break;
      double W_lo = 1e9, W_hi = -1e9, L_lo = 1e9, L_hi = -1e9;
      for (const auto& p : pts[static_cast<size_t>(f.body)]) {
        if (p.z() > zmin + 0.01) continue;
        W_lo = std::min(W_lo, p.head<2>().dot(lateral));
        W_hi = std::max(W_hi, p.head<2>().dot(lateral));
        L_lo = std::min(L_lo, p.head<2>().dot(heading));
        L_hi = std::max(L_hi, p.head<2>().dot(heading));
      }
      // Only a foot that is a sole (5 cm or more across within 1 cm of its lowest point): a ball
      // or a rounded tip stays a point.
      const bool sole_sized = std::max(W_hi - W_lo, L_hi - L_lo) >= kSoleSpan_m;
      const bool wider = (W_hi - W_lo) - (w_hi - w_lo) > 0.005 || (L_hi - L_lo) - (l_hi - l_lo) > 0.005;
      if (!wider || !sole_sized) break;
    }
    band = std::min(band, 0.01);
    double span_x = 0, span_y = 0;
    {
      double ax = 1e9, bx = -1e9, ay = 1e9, by = -1e9;
      for (const auto& p : sole) {
        const Eigen::Vector2d q = p.head<2>();
        ax = std::min(ax, q.dot(heading));
        bx = std::max(bx, q.dot(heading));
        ay = std::min(ay, q.dot(lateral));
        by = std::max(by, q.dot(lateral));
      }
      span_x = bx - ax;
      span_y = by - ay;
    }
    std::vector<Eigen::Vector3d> chosen;
    const bool narrow = std::max(span_x, span_y) < kPointFootSpan_m;
    if (narrow || few_joints) {
      f.point_foot = true;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const auto& p : sole) c += p;
      c /= static_cast<double>(sole.size());
      c.z() = zmin;
      chosen.push_back(c);
      // The bottom of a sphere of the foot (a ball foot): the simulator rolls it (its radius).
      for (const auto& g : d.geometries) {
        if (g.type != model::GeometryType::Sphere || g.link != f.body) continue;
        const Eigen::Vector3d centre = (L.body_pose[static_cast<size_t>(g.link)] * g.placement).translation();
        if (std::abs(centre.z() - g.radius - zmin) < 1e-6 && (centre.head<2>() - c.head<2>()).norm() < 1e-3 && g.radius > f.radius) {
          f.radius = g.radius;
        }
      }
    } else {
      std::vector<Eigen::Vector2d> flat;
      for (const auto& p : sole) flat.push_back(p.head<2>());
      const std::vector<Eigen::Vector2d> hull = convexHull(flat);
      std::vector<Eigen::Vector2d> dirs;
      if (std::min(span_x, span_y) < kPointFootSpan_m) {
        const Eigen::Vector2d a = span_x >= span_y ? heading : lateral;
        dirs = {a, -a};
      } else {
        dirs = {heading + lateral, heading - lateral, -heading - lateral, -heading + lateral};
      }
      for (const auto& dir : dirs) {
        size_t best = 0;
        for (size_t k = 1; k < hull.size(); ++k) {
          if (hull[k].dot(dir) > hull[best].dot(dir) + 1e-12) best = k;
        }
        const Eigen::Vector3d p(hull[best].x(), hull[best].y(), zmin);
        bool dup = false;
        for (const auto& c : chosen) dup = dup || (c - p).norm() < 1e-6;
        if (!dup) chosen.push_back(p);
      }
    }
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& c : chosen) centre += c;
    centre /= static_cast<double>(chosen.size());
    Eigen::Isometry3d sole_world = Eigen::Isometry3d::Identity();
    sole_world.linear() = Eigen::AngleAxisd(std::atan2(heading.y(), heading.x()), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    sole_world.translation() = centre;
    f.sole_in_body = X.inverse() * sole_world;
    for (const auto& c : chosen) {
      f.points_world.push_back(c);
      Eigen::Vector3d local = sole_world.inverse() * c;
      local.z() = 0.0;
      f.points.push_back(local);
    }
    f.source =
        (f.point_foot
             ? (narrow ? "the lowest point of "
                       : "the centre of the lowest " + formatNumber(std::round(band * 1000.0), 2) + " mm (a point foot: its leg has " +
                             std::to_string(leg_joints) + " joints, too few to hold the foot's orientation) of ")
             : "the extreme points, along the foot's diagonals, of the lowest " + formatNumber(std::round(band * 1000.0), 2) + " mm of ") +
        shapes[static_cast<size_t>(f.body)] + " in the posture";
  }
  // A foot above the others' level: the robot does not stand on it in this posture.
  for (const auto& f : L.feet) {
    double z = 1e18;
    for (const auto& p : f.points_world) z = std::min(z, p.z());
    if (z > L.lowest_z + kFootInAir_m) {
      L.warnings.push_back("foot on link '" + f.link + "' is " + formatNumber((z - L.lowest_z) * 1000.0, 3) +
                           " mm above the lowest foot in the posture: the robot does not stand on it (is the posture one of both legs?)");
    }
  }
  // Sides. Names tell left from right where they can (left_, l_, LLEG, LHip...); where the named
  // left is at -y the robot faces -x in its base frame, and forward is -x.
  const bool leg_letters = L.feet.size() >= 3;
  auto sideOfLimb = [&](const std::vector<int>& bodies) {
    int vote = 0;
    for (int b : bodies) {
      vote += sideOfName(d.links[static_cast<size_t>(b)].name, leg_letters);
      const model::LinkDescription& l = d.links[static_cast<size_t>(b)];
      vote += sideOfName(l.parent_joint >= 0 ? d.joints[static_cast<size_t>(l.parent_joint)].name
                                             : d.coupled_joints[static_cast<size_t>(l.parent_coupled)].name,
                         leg_letters);
    }
    return vote > 0 ? 1 : (vote < 0 ? -1 : 0);
  };
  std::vector<int> foot_side;
  for (size_t k = 0; k < L.feet.size(); ++k) foot_side.push_back(sideOfLimb(limbs[static_cast<size_t>(foot_limb[k])].all));
  {
    // The named left feet's mean y against the named right feet's (any number of feet).
    double y_left = 0.0, y_right = 0.0;
    int n_left = 0, n_right = 0;
    for (size_t k = 0; k < L.feet.size(); ++k) {
      if (foot_side[k] > 0) y_left += L.feet[k].points_world[0].y(), ++n_left;
      if (foot_side[k] < 0) y_right += L.feet[k].points_world[0].y(), ++n_right;
    }
    if (n_left > 0 && n_right > 0) {
      L.forward = Eigen::Vector3d(y_left / n_left >= y_right / n_right ? 1.0 : -1.0, 0.0, 0.0);
      L.sides_from = "names";
    }
  }
  const Eigen::Vector3d left_dir = Eigen::Vector3d::UnitZ().cross(L.forward);
  // Feet: two LEFT/RIGHT; four FRONT/HIND x LEFT/RIGHT; else FOOT_k.
  if (L.feet.size() == 2) {
    const bool first_left = L.feet[0].points_world[0].dot(left_dir) > L.feet[1].points_world[0].dot(left_dir);
    L.feet[first_left ? 0 : 1].surface = "LEFT_FOOT";
    L.feet[first_left ? 1 : 0].surface = "RIGHT_FOOT";
  } else if (L.feet.size() == 4) {
    // About the feet's centroid (the centre of mass may stand off it: a zero posture with every
    // foot forward of its hip).
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const auto& f : L.feet) centroid += L.body_pose[static_cast<size_t>(f.body)] * f.sole_in_body.translation();
    centroid /= 4.0;
    for (auto& f : L.feet) {
      const Eigen::Vector3d w = L.body_pose[static_cast<size_t>(f.body)] * f.sole_in_body.translation() - centroid;
      f.surface = std::string(w.dot(L.forward) >= 0.0 ? "FRONT_" : "HIND_") + (w.dot(left_dir) >= 0.0 ? "LEFT_FOOT" : "RIGHT_FOOT");
    }
  } else {
    for (size_t k = 0; k < L.feet.size(); ++k) L.feet[k].surface = "FOOT_" + std::to_string(k + 1);
  }
  {
    std::map<std::string, int> seen;
    for (auto& f : L.feet) {
      if (seen[f.surface]++) f.surface += "_" + std::to_string(seen[f.surface]);
    }
  }

  // Arms: the other limbs whose chain has 3 or more joints up to the hand; two on opposite sides
  // are the left and right arms, else (a robot without legs) the one with the most joints. The
  // hand is the first body of the chain that branches (a palm with fingers), else its last body
  // (or the one before, when the last is a small finger: less than 40 % of it).
  struct Candidate {
    int limb;
    int joints;
    int hand;
    double side;  // > 0 left of the robot
    int named;    // the names' side
  };
  std::vector<Candidate> cands;
  for (size_t li = 0; li < limbs.size(); ++li) {
    if (std::find(foot_limb.begin(), foot_limb.end(), static_cast<int>(li)) != foot_limb.end()) continue;
    const Limb& limb = limbs[li];
    int hand = limb.bodies.back();
    size_t n = limb.bodies.size();
    for (size_t k = 0; k < limb.bodies.size(); ++k) {
      if (children[static_cast<size_t>(limb.bodies[k])].size() >= 2) {
        hand = limb.bodies[k];
        n = k + 1;
        break;
      }
    }
    // A finger moves on a short stroke: prismatic, or revolute within half a turn (a wrist that
    // turns all the way round is not one).
    auto fingerJoint = [&](int b) {
      const model::LinkDescription& l = d.links[static_cast<size_t>(b)];
      if (l.parent_joint < 0) return true;  // a coupled (mimic) joint
      const model::JointDescription& J = d.joints[static_cast<size_t>(l.parent_joint)];
      return J.type == model::JointType::Prismatic || (std::isfinite(J.lower) && std::isfinite(J.upper) && J.upper - J.lower <= kPi + 1e-9);
    };
    if (hand == limb.bodies.back() && n >= 2 && fingerJoint(hand)) {
      const int p = limb.bodies[n - 2];
      if (subtree_mass[static_cast<size_t>(hand)] < 0.4 * d.links[static_cast<size_t>(p)].mass) {
        hand = p;
        --n;
      }
    }
    if (n < 3) continue;
    const Eigen::Vector3d first = L.body_pose[static_cast<size_t>(limb.bodies.front())].translation() - L.com;
    cands.push_back({static_cast<int>(li), static_cast<int>(n), hand, first.dot(left_dir), sideOfLimb(limb.all)});
  }
  std::sort(cands.begin(), cands.end(),
            [](const Candidate& a, const Candidate& b) { return a.joints > b.joints || (a.joints == b.joints && a.limb < b.limb); });
  std::vector<std::pair<Candidate, std::string>> arms;
  for (size_t i = 0; i < cands.size() && arms.empty(); ++i) {
    for (size_t j = i + 1; j < cands.size(); ++j) {
      const bool opposite = cands[i].named * cands[j].named < 0 || (cands[i].named == 0 && cands[i].side * cands[j].side < 0.0);
      if (opposite && std::abs(cands[i].joints - cands[j].joints) <= 1) {
        const bool i_left = cands[i].named != 0 ? cands[i].named > 0 : cands[i].side > 0.0;
        arms.push_back({cands[i], i_left ? "LEFT" : "RIGHT"});
        arms.push_back({cands[j], i_left ? "RIGHT" : "LEFT"});
        break;
      }
    }
  }
  if (arms.empty() && !cands.empty() && !L.legged) arms.push_back({cands[0], ""});
  for (const auto& [c, side] : arms) {
    const Limb& limb = limbs[static_cast<size_t>(c.limb)];
    ArmLayout a;
    a.side = side;
    a.end_body = c.hand;
    a.end_link = d.links[static_cast<size_t>(c.hand)].name;
    {
      const model::LinkDescription& l = d.links[static_cast<size_t>(limb.bodies.front())];
      a.first_joint = l.parent_joint >= 0 ? l.parent_joint : d.coupled_joints[static_cast<size_t>(l.parent_coupled)].master;
    }
    a.shoulder = L.body_pose[static_cast<size_t>(limb.bodies.front())].translation();
    // The grasp point: between the fingertips when the hand has two fingers or more (each
    // finger's tip: the body of its subtree whose geometry's centre is farthest from the hand's
    // origin), else the end of the hand (its geometry's extreme along the direction from its
    // joint to its centre: the end of a forearm, a flange's face).
    const std::vector<int>& fingers = children[static_cast<size_t>(c.hand)];
    const Eigen::Vector3d hand_origin = L.body_pose[static_cast<size_t>(c.hand)].translation();
    auto bodyCentre = [&](int b) {
      Eigen::Vector3d s = Eigen::Vector3d::Zero();
      for (const auto& p : pts[static_cast<size_t>(b)]) s += p;
      return Eigen::Vector3d(s / static_cast<double>(std::max<size_t>(pts[static_cast<size_t>(b)].size(), 1)));
    };
    auto centreOf = [&](const std::vector<int>& roots, int& count) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      count = 0;
      std::vector<int> stack = roots;
      while (!stack.empty()) {
        const int k = stack.back();
        stack.pop_back();
        for (const auto& p : pts[static_cast<size_t>(k)]) {
          sum += p;
          ++count;
        }
        for (int ch : children[static_cast<size_t>(k)]) stack.push_back(ch);
      }
      return Eigen::Vector3d(sum / static_cast<double>(std::max(count, 1)));
    };
    int count = 0;
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    bool between_fingers = false, at_end = false;
    if (fingers.size() >= 2) {
      int tips = 0;
      for (int f : fingers) {
        int tip = f;
        double far = -1.0;
        std::vector<int> stack{f};
        while (!stack.empty()) {
          const int k = stack.back();
          stack.pop_back();
          const double r = (bodyCentre(k) - hand_origin).norm();
          if (r > far) {
            far = r;
            tip = k;
          }
          for (int ch : children[static_cast<size_t>(k)]) stack.push_back(ch);
        }
        g += bodyCentre(tip);
        ++tips;
      }
      g /= static_cast<double>(tips);
      between_fingers = true;
    } else {
      g = centreOf({c.hand}, count);
      const Eigen::Vector3d dir = g - hand_origin;
      if (dir.norm() > 0.01 && count > 0) {
        const Eigen::Vector3d u = dir.normalized();
        double ext = 0.0;
        std::vector<int> stack{c.hand};
        while (!stack.empty()) {
          const int k = stack.back();
          stack.pop_back();
          for (const auto& p : pts[static_cast<size_t>(k)]) ext = std::max(ext, (p - g).dot(u));
          for (int ch : children[static_cast<size_t>(k)]) stack.push_back(ch);
        }
        g += ext * u;
        at_end = true;
      }
    }
    a.grasp_world = g;
    a.grasp_in_body = L.body_pose[static_cast<size_t>(c.hand)].inverse() * g;
    std::vector<Eigen::Vector3d> chain;
    for (int b : limb.bodies) {
      chain.push_back(L.body_pose[static_cast<size_t>(b)].translation());
      if (b == c.hand) break;
    }
    chain.push_back(g);
    a.reach = chainLength(chain);
    a.source =
        (between_fingers ? "between the tips of the " + std::to_string(fingers.size()) + " fingers of the hand, link '" + a.end_link + "'"
         : at_end        ? "the end of the hand, link '" + a.end_link + "' and what it carries (its geometry's extreme away from its joint)"
                         : "the centre of the geometry of the hand, link '" + a.end_link + "' and what it carries") +
        " (the end of the " + std::to_string(c.joints) + "-joint chain from joint '" + d.joints[static_cast<size_t>(a.first_joint)].name +
        "')";
    L.arms.push_back(a);
  }
  if (L.arms.empty()) L.notes.push_back("no arm found (no chain of 3 or more joints that is not a leg)");

  // Loads: a leg joint holds the rest of the robot (shared by the feet), any other its subtree.
  std::vector<double> sub_m(static_cast<size_t>(nb), 0.0);
  std::vector<Eigen::Vector3d> sub_h(static_cast<size_t>(nb), Eigen::Vector3d::Zero());
  std::vector<bool> has_foot(static_cast<size_t>(nb), false);
  for (const auto& f : L.feet) has_foot[static_cast<size_t>(f.body)] = true;
  for (int b = nb - 1; b >= 0; --b) {
    const auto& l = d.links[static_cast<size_t>(b)];
    sub_m[static_cast<size_t>(b)] += l.mass;
    sub_h[static_cast<size_t>(b)] += l.mass * (L.body_pose[static_cast<size_t>(b)] * l.com);
    if (b > 0) {
      const size_t p = static_cast<size_t>(parent[static_cast<size_t>(b)]);
      sub_m[p] += sub_m[static_cast<size_t>(b)];
      sub_h[p] += sub_h[static_cast<size_t>(b)];
      if (has_foot[static_cast<size_t>(b)]) has_foot[p] = true;
    }
  }
  const double M = L.mass;
  const Eigen::Vector3d H = M * L.com;
  const int n_feet = std::max<int>(1, static_cast<int>(L.feet.size()));
  for (size_t j = 0; j < d.joints.size(); ++j) {
    const auto& J = d.joints[j];
    const size_t b = static_cast<size_t>(J.child_link);
    const Eigen::Vector3d o = L.body_pose[b].translation();
    JointLoad load;
    if (L.legged && has_foot[b]) {
      const double m_rest = M - sub_m[b];
      const Eigen::Vector3d c_rest = m_rest > 0.0 ? Eigen::Vector3d((H - sub_h[b]) / m_rest) : o;
      load.mass = m_rest / n_feet;
      load.lever = (c_rest - o).norm();
      load.inertia = load.mass * load.lever * load.lever;
      load.what = "the robot above it (" + formatNumber(m_rest, 3) + " kg) shared by " + std::to_string(n_feet) + " feet";
    } else {
      load.mass = sub_m[b];
      const Eigen::Vector3d c = load.mass > 0.0 ? Eigen::Vector3d(sub_h[b] / load.mass) : o;
      load.lever = (c - o).norm();
      // The subtree's inertia about the joint axis.
      const Eigen::Vector3d a = L.body_pose[b].linear() * J.axis;
      double I = 0.0;
      std::vector<int> stack{static_cast<int>(b)};
      while (!stack.empty()) {
        const int k = stack.back();
        stack.pop_back();
        const auto& l = d.links[static_cast<size_t>(k)];
        const Eigen::Matrix3d R = L.body_pose[static_cast<size_t>(k)].linear();
        const Eigen::Vector3d r = L.body_pose[static_cast<size_t>(k)] * l.com - o;
        I +=
            J.type == model::JointType::Prismatic
                ? l.mass
                : a.dot((R * l.inertia * R.transpose() + l.mass * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose())) * a);
        for (int c : children[static_cast<size_t>(k)]) stack.push_back(c);
      }
      load.inertia = I;
      load.what = "its subtree (" + formatNumber(load.mass, 3) + " kg)";
    }
    L.loads.push_back(load);
  }
  return L;
}

ServoGains sizeServo(const model::RobotDescription& d, const RobotLayout& layout, int joint, double dt) {
  const auto& J = d.joints[static_cast<size_t>(joint)];
  const JointLoad& load = layout.loads[static_cast<size_t>(joint)];
  const bool prismatic = J.type == model::JointType::Prismatic;
  constexpr double kDeflection = 0.005;  // rad (or m) of static deflection under the load
  constexpr double kSaturation = 0.5;    // rad (or m) at which the effort limit is reached at least
  // The lever: the distance to the load's centre of mass, at least its radius of gyration about
  // the joint (a load centred on the joint still swings its mass around it), at least 5 cm.
  const double gyration = load.mass > 0.0 ? std::sqrt(load.inertia / load.mass) : 0.0;
  const double lever = std::max({load.lever, gyration, 0.05});
  const double torque = prismatic ? load.mass * kGravity : load.mass * kGravity * lever;
  double kp = torque / kDeflection;
  std::string why = prismatic ? "load " + formatNumber(load.mass, 3) + " kg (" + load.what + "): " + formatNumber(torque, 3) + " N / 5 mm"
                              : "load " + formatNumber(load.mass, 3) + " kg at " + formatNumber(lever, 2) + " m (" + load.what +
                                    "): " + formatNumber(torque, 3) + " N m / 5 mrad";
  if (std::isfinite(J.effort_limit) && J.effort_limit / kSaturation > kp) {
    kp = J.effort_limit / kSaturation;
    why = "effort " + formatNumber(J.effort_limit, 3) + " reached at 0.5 " + (prismatic ? "m" : "rad");
  }
  kp = std::max(kp, 1.0);
  const double I = std::max(load.inertia, prismatic ? 1e-3 : load.mass * 0.05 * 0.05 + 1e-6);
  double kd = 4.0 * dt * kp;
  std::string why_d = "4 dt kp";
  const double crit = 1.4 * std::sqrt(kp * I);
  if (crit > kd) {
    kd = crit;
    why_d = "damping ratio 0.7 on " + formatNumber(I, 3) + (prismatic ? " kg" : " kg m^2");
  }
  // Two significant digits: these are guesses.
  auto round2 = [](double v) {
    if (v <= 0.0) return v;
    const double e = std::pow(10.0, std::floor(std::log10(v)) - 1.0);
    return std::round(v / e) * e;
  };
  return {round2(kp), round2(kd), why + "; kd: " + why_d};
}

}  // namespace lexdyn::robot
