#include "harness/robot/srdf.hpp"

#include "lexdyn/common/error.hpp"
#include "lexdyn/common/format.hpp"
#include "lexdyn/common/input_text.hpp"

#include <tinyxml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace lexdyn::robot {

namespace {

std::string attr(const TiXmlElement* e, const char* name) {
  const char* v = e ? e->Attribute(name) : nullptr;
  return v ? v : "";
}

// Every value of a joint's `value` attribute (one per coordinate: a free-flyer's root joint has 7).
bool numbers(const std::string& text, std::vector<double>& out) {
  std::istringstream in(text);
  std::string tok;
  while (in >> tok) {
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(tok.c_str(), &end);
    if (end != tok.c_str() + tok.size() || errno == ERANGE || !std::isfinite(v)) return false;
    out.push_back(v);
  }
  return !out.empty();
}

}  // namespace

Srdf readSrdf(const std::string& path, const model::RobotDescription& d, ProblemList& problems, bool skip_unknown) {
  Srdf s;
  s.path = path;
  const std::string text = readTextFile(path, "SRDF");
  auto at = [&](const TiXmlElement* e) { return path + ":" + std::to_string(e->Row()); };
  TiXmlDocument doc;
  doc.Parse(text.c_str());
  if (doc.Error())
    problems.fatal(path + (doc.ErrorRow() > 0 ? ":" + std::to_string(doc.ErrorRow()) : ""),
                   std::string("XML syntax error: ") + doc.ErrorDesc());
  const TiXmlElement* robot = doc.RootElement();
  if (!robot || std::string(robot->Value()) != "robot") problems.fatal(path, "expected a <robot> root element (an SRDF)");
  s.robot_name = attr(robot, "name");
  if (!s.robot_name.empty() && s.robot_name != d.name) {
    problems.warning(at(robot), "the SRDF is for robot '" + s.robot_name + "', the URDF describes '" + d.name + "'");
  }
  auto knownLink = [&](const std::string& n) { return d.findFrame(n) >= 0; };
  auto lockedJoint = [&](const std::string& n) {
    for (const auto& l : d.locked_joints) {
      if (l.name == n) return true;
    }
    return false;
  };
  auto coupledJoint = [&](const std::string& n) {
    for (const auto& c : d.coupled_joints) {
      if (c.name == n) return true;
    }
    return false;
  };
  for (const TiXmlElement* v = robot->FirstChildElement("virtual_joint"); v; v = v->NextSiblingElement("virtual_joint")) {
    s.virtual_joints.push_back(attr(v, "name"));
  }
  for (const TiXmlElement* g = robot->FirstChildElement("group"); g; g = g->NextSiblingElement("group")) {
    SrdfGroup grp;
    grp.name = attr(g, "name");
    grp.line = g->Row();
    for (const TiXmlElement* c = g->FirstChildElement(); c; c = c->NextSiblingElement()) {
      const std::string kind = c->Value();
      if (kind == "chain") {
        const std::string base = attr(c, "base_link"), tip = attr(c, "tip_link");
        for (const std::string& l : {base, tip}) {
          if (!knownLink(l))
            problems.error(at(c), "group '" + grp.name + "': <chain> names link '" + l + "', which the URDF does not have");
        }
        grp.chains.emplace_back(base, tip);
      } else if (kind == "link") {
        grp.links.push_back(attr(c, "name"));
      } else if (kind == "joint") {
        grp.joints.push_back(attr(c, "name"));
      } else if (kind == "group") {
        grp.subgroups.push_back(attr(c, "name"));
      }
    }
    s.groups.push_back(grp);
  }
  for (const TiXmlElement* e = robot->FirstChildElement("end_effector"); e; e = e->NextSiblingElement("end_effector")) {
    SrdfEndEffector ee{attr(e, "name"), attr(e, "parent_link"), attr(e, "group"), e->Row()};
    if (!knownLink(ee.parent_link)) {
      problems.error(at(e), "end effector '" + ee.name + "': parent_link '" + ee.parent_link + "' is not a link of the URDF");
      continue;
    }
    s.end_effectors.push_back(ee);
  }
  std::vector<std::string> prefixes;  // namespace prefixes matched away (below)
  for (const TiXmlElement* st = robot->FirstChildElement("group_state"); st; st = st->NextSiblingElement("group_state")) {
    SrdfState state;
    state.name = attr(st, "name");
    state.group = attr(st, "group");
    state.line = st->Row();
    if (state.name.empty()) {
      problems.error(at(st), "<group_state> without a name");
      continue;
    }
    std::vector<std::string> dropped;
    for (const TiXmlElement* j = st->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
      std::string name = attr(j, "name");
      // A namespace prefix ('baxter/left_s0', as a multi-robot MoveIt configuration writes it)
      // on a name the URDF has without it: matched without the prefix, noted once per prefix.
      const size_t slash = name.rfind('/');
      if (d.findJoint(name) < 0 && slash != std::string::npos && slash + 1 < name.size()) {
        const std::string bare = name.substr(slash + 1);
        if (d.findJoint(bare) >= 0 || lockedJoint(bare) || coupledJoint(bare)) {
          const std::string prefix = name.substr(0, slash + 1);
          if (std::find(prefixes.begin(), prefixes.end(), prefix) == prefixes.end()) {
            prefixes.push_back(prefix);
            s.notes.push_back("SRDF joint names with the prefix '" + prefix + "' (e.g. '" + name + "', line " + std::to_string(j->Row()) +
                              ") matched to the URDF's joints without it");
          }
          name = bare;
        }
      }
      std::vector<double> v;
      if (!numbers(attr(j, "value"), v)) {
        problems.error(at(j), "group state '" + state.name + "': joint '" + name + "': value=\"" + attr(j, "value") +
                                  "\" is not a list of finite numbers");
        continue;
      }
      const bool virtual_joint = std::find(s.virtual_joints.begin(), s.virtual_joints.end(), name) != s.virtual_joints.end();
      if (virtual_joint || v.size() == 7) {
        dropped.push_back(name + " (the base's pose: found by the start's equilibrium instead)");
        continue;
      }
      if (d.findJoint(name) < 0) {
        if (lockedJoint(name)) {
          dropped.push_back(name + " (locked by the loader: not a joint of the model)");
          continue;
        }
        if (coupledJoint(name)) {
          dropped.push_back(name + " (a mimic joint: it follows its master)");
          continue;
        }
        if (skip_unknown) {
          dropped.push_back(name + " (not a joint of the URDF; --srdf-skip-unknown)");
          continue;
        }
        problems.error(at(j), "group state '" + state.name + "' names joint '" + name +
                                  "', which the URDF does not have (an SRDF written for another version of the robot? "
                                  "--srdf-skip-unknown leaves such joints out)");
        continue;
      }
      if (v.size() != 1) {
        problems.error(at(j),
                       "group state '" + state.name + "': joint '" + name + "' has " + std::to_string(v.size()) + " values, expected 1");
        continue;
      }
      state.values.emplace_back(name, v[0]);
    }
    for (const auto& x : dropped) s.notes.push_back("SRDF state '" + state.name + "': dropped " + x);
    // A state given once per group (MoveIt configurations often define `ready` for each arm and
    // leg): one posture of all of them, with a note; a joint given twice keeps its first value.
    auto same = std::find_if(s.states.begin(), s.states.end(), [&](const SrdfState& o) { return o.name == state.name; });
    if (same != s.states.end()) {
      int added = 0;
      for (const auto& [joint, value] : state.values) {
        const bool known = std::any_of(same->values.begin(), same->values.end(), [&](const auto& jv) { return jv.first == joint; });
        if (known) {
          const double first =
              std::find_if(same->values.begin(), same->values.end(), [&](const auto& jv) { return jv.first == joint; })->second;
          if (first != value) {
            s.notes.push_back("SRDF state '" + state.name + "' (groups '" + same->group + "' and '" + state.group + "'): joint '" + joint +
                              "' given twice, " + formatNumber(first) + " and " + formatNumber(value) + ": the first is kept");
          }
          continue;
        }
        same->values.emplace_back(joint, value);
        ++added;
      }
      s.notes.push_back("SRDF state '" + state.name + "' of group '" + state.group + "' (line " + std::to_string(state.line) +
                        ") merged with the one of group '" + same->group + "' (line " + std::to_string(same->line) +
                        "): " + std::to_string(added) + " more joint(s)");
      same->group += "+" + state.group;
      continue;
    }
    s.states.push_back(state);
  }
  return s;
}

}  // namespace lexdyn::robot
