#include "harness/cli/robot_cmd.hpp"

#include "harness/robot/mesh.hpp"
#include "harness/robot/robot_check.hpp"
#include "harness/robot/robot_init.hpp"

#include <CLI/CLI.hpp>

#include "lexdyn/common/error.hpp"

#include <chrono>
#include <cstdio>

namespace lexdyn::cli {

void addRobotCommands(CLI::App& app, RobotCommand& c) {
  c.robot = app.add_subcommand("robot", "bring a robot in: draft its data file and cases from its URDF (init), check a model (check)");
  c.robot->require_subcommand(1);
  c.init = c.robot->add_subcommand("init", "draft DIR/<robot>.yaml, DIR/stand.yaml and DIR/reach.yaml from a URDF (docs/model.md)");
  c.init->add_option("urdf", c.input, "the robot's URDF, as its package ships it")->required();
  c.init->add_option("--out", c.out, "a new folder for the drafted files")->required();
  c.init->add_option("--srdf", c.srdf, "the robot's SRDF: its group states become postures, its groups name limbs");
  c.init->add_flag("--srdf-skip-unknown", c.srdf_skip_unknown, "leave out the SRDF's joints the URDF does not have (else an error)");
  c.init
      ->add_option("--mimic", c.mimic,
                   "the URDF's <mimic> joints: coupled (move with their masters; the default) or locked (held at the posture)")
      ->check(CLI::IsMember({"coupled", "locked"}));
  c.init->add_option("--package-path", c.package_paths, "a folder to look for package://NAME/ in (repeatable; also $ROS_PACKAGE_PATH)");
  c.init->add_option("--base", c.base, "free_flyer or fixed (default: guessed from the URDF: fixed for a `world` root or no legs)");
  c.init->add_option("--posture", c.posture, "the SRDF group state to stand in (default: half_sitting, standing, home, ... or the first)");
  c.init->add_flag("--strict", c.strict, "read the URDF with the strict rules (every lenient reading is an error)");
  c.init->add_flag("--allow-missing-meshes", c.allow_missing_meshes, "a mesh file that cannot be found is a warning, not an error");
  c.check = c.robot->add_subcommand("check", "print what to check before trusting a model, and draw it (docs/model.md)");
  c.check->add_option("input", c.input, "a robot data file, a case file, or a URDF")->required();
  c.check->add_option("--urdf", c.urdf, "with a data file: its URDF (default: the data file's `urdf` key)");
  c.check->add_option("--package-path", c.package_paths, "a folder to look for package://NAME/ in (repeatable)");
  c.check->add_option("--posture", c.posture, "the posture to check (default: the case's, else the data file's first)");
  c.check->add_option("--png", c.png, "the picture to write (default: <input folder>/<robot>_posture.png; - for none)");
  c.check->add_flag("--strict", c.strict, "read the URDF with the strict rules");
  c.mesh = c.robot->add_subcommand("mesh", "convert a mesh file (any format libassimp reads) to binary STL, as robot init reads it");
  c.mesh->add_option("mesh", c.input, "the mesh file (STL, DAE, OBJ, glTF, ...)")->required();
  c.mesh->add_option("--out", c.out, "the binary STL to write")->required();
  c.mesh
      ->add_option(
          "--up-axis", c.up_axis,
          "ignore: a COLLADA file's coordinates as written (ROS's tools); file: turned by its <up_axis> (the data file's mesh_up_axis)")
      ->check(CLI::IsMember({"ignore", "file"}));
}

int runRobotCommand(const RobotCommand& c) {
  if (*c.init) {
    const auto t0 = std::chrono::steady_clock::now();
    robot::InitOptions o;
    o.urdf = c.input;
    o.srdf = c.srdf;
    o.srdf_skip_unknown = c.srdf_skip_unknown;
    o.mimic = c.mimic;
    o.out_dir = c.out;
    o.package_paths = c.package_paths;
    o.base = c.base;
    o.posture = c.posture;
    o.strict = c.strict;
    o.allow_missing_meshes = c.allow_missing_meshes;
    const robot::InitResult r = robot::initRobot(o);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "robot init: %s\n", c.input.c_str());
    for (const auto& s : r.summary) std::fprintf(stderr, "  %s\n", s.c_str());
    if (!r.warnings.empty()) {
      std::fprintf(stderr, "  %zu warning(s):\n", r.warnings.size());
      for (const auto& w : r.warnings) std::fprintf(stderr, "    %s\n", w.c_str());
    }
    for (const auto& f : r.files) std::fprintf(stderr, "  wrote %s\n", f.c_str());
    std::fprintf(stderr, "  (%.2f s) next: lexdyn-harness robot check %s, then lexdyn-harness run %s/stand.yaml --out OUT\n", wall,
                 r.files.front().c_str(), c.out.c_str());
    return 0;
  }
  if (*c.mesh) {
    const robot::Mesh m = robot::placedMesh(robot::readMesh(c.input), Eigen::Vector3d::Ones(), c.up_axis == "file");
    const std::string tmp = c.out + ".partial";
    robot::writeBinaryStl(tmp, m);
    if (std::rename(tmp.c_str(), c.out.c_str()) != 0) throw InputError(c.out, "cannot write");
    std::fprintf(stderr, "robot mesh: %s: %zu triangles -> %s\n", c.input.c_str(), m.triangles.size(), c.out.c_str());
    return 0;
  }
  robot::CheckOptions o;
  o.input = c.input;
  o.urdf = c.urdf;
  o.package_paths = c.package_paths;
  o.posture = c.posture;
  o.png = c.png;
  o.strict = c.strict;
  const robot::CheckReport r = robot::checkRobot(o);
  std::fputs(r.text.c_str(), stdout);
  return 0;
}

}  // namespace lexdyn::cli
