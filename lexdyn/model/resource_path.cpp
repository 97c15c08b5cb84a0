#include "lexdyn/model/resource_path.hpp"

#include <algorithm>
#include <cstdlib>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace lexdyn::model {

namespace fs = std::filesystem;

namespace {

bool isFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

// The <name> of a package.xml, "" when there is none.
std::string packageXmlName(const fs::path& dir) {
  std::ifstream in(dir / "package.xml");
  if (!in) return {};
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  const size_t a = text.find("<name>");
  const size_t b = text.find("</name>", a == std::string::npos ? 0 : a);
  if (a == std::string::npos || b == std::string::npos) return {};
  std::string name = text.substr(a + 6, b - a - 6);
  const size_t s = name.find_first_not_of(" \t\r\n"), e = name.find_last_not_of(" \t\r\n");
  return s == std::string::npos ? std::string() : name.substr(s, e - s + 1);
}

bool isPackage(const fs::path& dir, const std::string& name) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return false;
  const std::string declared = packageXmlName(dir);
  return declared.empty() ? dir.filename() == name : declared == name;
}

// A folder below `root` (at most `depth` levels) that is package `name`; sorted traversal, so the
// result does not depend on the file system's order.
fs::path findPackage(const fs::path& root, const std::string& name, int depth) {
  if (isPackage(root / name, name)) return root / name;
  if (depth == 0) return {};
  std::error_code ec;
  std::vector<fs::path> dirs;
  for (fs::directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->is_directory(ec) && it->path().filename().string()[0] != '.') dirs.push_back(it->path());
  }
  std::sort(dirs.begin(), dirs.end());
  for (const fs::path& d : dirs) {
    if (isPackage(d, name)) return d;
  }
  for (const fs::path& d : dirs) {
    const fs::path found = findPackage(d, name, depth - 1);
    if (!found.empty()) return found;
  }
  return {};
}

}  // namespace

std::vector<std::string> packageSearchPath(const std::vector<std::string>& package_paths, bool use_ros) {
  std::vector<std::string> out = package_paths;
  if (use_ros) {
    if (const char* env = std::getenv("ROS_PACKAGE_PATH")) {
      std::stringstream ss(env);
      std::string item;
      while (std::getline(ss, item, ':')) {
        if (!item.empty()) out.push_back(item);
      }
    }
  }
  return out;
}

ResolvedResource resolveResource(const std::string& uri, const std::string& urdf_path, const std::vector<std::string>& search) {
  ResolvedResource r;
  const fs::path urdf_dir = fs::path(urdf_path).parent_path().empty() ? fs::path(".") : fs::path(urdf_path).parent_path();
  const std::string kPackage = "package://", kFile = "file://";
  if (uri.compare(0, kPackage.size(), kPackage) == 0) {
    std::string rest = uri.substr(kPackage.size());
    while (!rest.empty() && rest[0] == '/') rest.erase(0, 1);  // package:///NAME/... (an empty host)
    const size_t slash = rest.find('/');
    const std::string name = rest.substr(0, slash);
    const std::string inside = slash == std::string::npos ? std::string() : rest.substr(slash + 1);
    // The URDF's own package: a folder above the URDF that is package `name`.
    for (fs::path d = fs::absolute(urdf_dir); !d.empty(); d = d.parent_path()) {
      if (isPackage(d, name) && isFile(d / inside)) {
        r.path = (d / inside).lexically_normal().string();
        return r;
      }
      if (d == d.root_path()) break;
    }
    std::string found_without_file;
    for (fs::path d = fs::absolute(urdf_dir); !d.empty(); d = d.parent_path()) {
      if (isPackage(d, name)) {
        found_without_file = d.string();
        break;
      }
      if (d == d.root_path()) break;
    }
    for (const std::string& root : search) {
      const fs::path pkg = findPackage(root, name, 4);
      if (!pkg.empty() && isFile(pkg / inside)) {
        r.path = (pkg / inside).lexically_normal().string();
        return r;
      }
      if (!pkg.empty() && found_without_file.empty()) found_without_file = pkg.string();
    }
    if (!found_without_file.empty()) {
      r.package_found = true;
      r.searched = "package '" + name + "' is " + found_without_file + ", which has no file " + inside;
      // A name that differs only in case (a package written on a case-insensitive file system).
      const fs::path want = fs::path(found_without_file) / inside;
      std::error_code ec;
      for (const auto& e : fs::directory_iterator(want.parent_path(), ec)) {
        std::string a = e.path().filename().string(), b = want.filename().string();
        if (a.size() != b.size() || a == b) continue;
        bool same = true;
        for (size_t k = 0; k < a.size() && same; ++k)
          same = std::tolower(static_cast<unsigned char>(a[k])) == std::tolower(static_cast<unsigned char>(b[k]));
        if (same) {
          r.searched += " (it has " + e.path().filename().string() + ", which differs in case only)";
          break;
        }
      }
      return r;
    }
    r.searched = "package '" + name + "' not found above " + urdf_dir.string();
    if (search.empty()) {
      r.searched += " (no package path: give --package-path DIR or set ROS_PACKAGE_PATH)";
    } else {
      std::string list;
      for (const std::string& s : search) list += (list.empty() ? "" : ":") + s;
      r.searched += " nor in the package path " + list;
    }
    return r;
  }
  std::string p = uri;
  if (p.compare(0, kFile.size(), kFile) == 0) p = p.substr(kFile.size());
  const fs::path candidate = fs::path(p).is_absolute() ? fs::path(p) : urdf_dir / p;
  if (isFile(candidate)) {
    r.path = candidate.lexically_normal().string();
  } else {
    r.searched = "no file " + candidate.lexically_normal().string();
  }
  return r;
}

}  // namespace lexdyn::model
