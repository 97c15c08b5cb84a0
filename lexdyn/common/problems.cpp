#include "lexdyn/common/problems.hpp"

#include <algorithm>
#include <cstdlib>

namespace lexdyn {

namespace {

// "file:line..." -> (file, line); line 0 when there is none.
std::pair<std::string, long> fileAndLine(const std::string& where) {
  const size_t colon = where.find(':');
  if (colon == std::string::npos) return {where, 0};
  char* end = nullptr;
  const long line = std::strtol(where.c_str() + colon + 1, &end, 10);
  if (end == where.c_str() + colon + 1) return {where, 0};
  return {where.substr(0, colon), line};
}

}  // namespace

void ProblemList::throwIfErrors() const {
  if (errors_.empty()) return;
  if (errors_.size() == 1) throw InputError(errors_[0].where, errors_[0].what);
  // Files in the order they were first named, lines ascending within a file (stable).
  std::vector<std::string> files;
  for (const Problem& p : errors_) {
    const std::string f = fileAndLine(p.where).first;
    if (std::find(files.begin(), files.end(), f) == files.end()) files.push_back(f);
  }
  std::vector<Problem> sorted = errors_;
  std::stable_sort(sorted.begin(), sorted.end(), [&](const Problem& a, const Problem& b) {
    const auto fa = fileAndLine(a.where), fb = fileAndLine(b.where);
    const long ia = std::find(files.begin(), files.end(), fa.first) - files.begin();
    const long ib = std::find(files.begin(), files.end(), fb.first) - files.begin();
    return ia != ib ? ia < ib : fa.second < fb.second;
  });
  // The files named, when they are not only the one this list reads (a data file's problems
  // listed with its URDF's).
  std::string text = std::to_string(errors_.size()) + " problems";
  if (files.size() > 1 || files.front() != file_) {
    text += " in ";
    for (size_t k = 0; k < files.size(); ++k) text += (k == 0 ? "" : (k + 1 == files.size() ? " and " : ", ")) + files[k];
  }
  text += ":";
  for (const Problem& p : sorted) text += "\n  " + p.text();
  throw InputError(file_, text);
}

void ProblemList::fatal(const std::string& where, const std::string& what) {
  errors_.push_back({where, what});
  ++hard_errors_;
  throwIfErrors();
  throw InputError(where, what);  // not reached: throwIfErrors threw
}

}  // namespace lexdyn
