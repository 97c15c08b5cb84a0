// `lexdyn-harness robot init | check` (docs/model.md, "Bringing your own robot").
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace lexdyn::cli {

struct RobotCommand {
  CLI::App* robot = nullptr;
  CLI::App *init = nullptr, *check = nullptr, *mesh = nullptr;
  std::string input, srdf, out, base, posture, urdf, png;
  std::vector<std::string> package_paths;
  bool strict = false, allow_missing_meshes = false, srdf_skip_unknown = false;
  std::string up_axis = "ignore";  // robot mesh --up-axis
  std::string mimic = "coupled";   // robot init --mimic
};

void addRobotCommands(CLI::App& app, RobotCommand& c);

/// Runs the chosen subcommand; throws InputError on bad input (exit code 2 in main).
int runRobotCommand(const RobotCommand& c);

}  // namespace lexdyn::cli
