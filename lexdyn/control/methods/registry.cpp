// The method registry (lexdyn/control/method.hpp). A built-in method is one file pair in this
// directory and one line in kBuiltin below (docs/architecture.md, "Adding a method").
#include <utility>

#include "lexdyn/common/error.hpp"
#include "lexdyn/control/method.hpp"
#include "lexdyn/control/methods/gauss_newton.hpp"
#include "lexdyn/control/methods/lexdyn_ah.hpp"
#include "lexdyn/control/methods/lexdyn_bfgs.hpp"
#include "lexdyn/control/methods/wls.hpp"

namespace lexdyn::control {

namespace {

std::vector<MethodInfo>& registry() {
  static std::vector<MethodInfo> methods = {
      methods::lexDynBfgsMethod(),
      methods::lexDynAhMethod(),
      methods::gaussNewtonMethod(),
      methods::wlsMethod(),
  };
  return methods;
}

std::string joined() {
  std::string s;
  for (const MethodInfo& m : registry()) s += (s.empty() ? "" : ", ") + m.name;
  return s;
}

}  // namespace

std::vector<std::string> methodNames() {
  std::vector<std::string> names;
  for (const MethodInfo& m : registry()) names.push_back(m.name);
  return names;
}

const MethodInfo& findMethod(const std::string& name, const std::string& where) {
  for (const MethodInfo& m : registry())
    if (m.name == name) return m;
  throw InputError(where, "expected one of " + joined() + ", found \"" + name + "\"");
}

void registerMethod(MethodInfo info) {
  const std::string where = "method \"" + info.name + "\"";
  if (info.name.empty()) throw InputError("method", "expected a name for the method");
  if (!info.make) throw InputError(where, "expected a factory");
  for (const MethodInfo& m : registry())
    if (m.name == info.name) throw InputError(where, "a method of this name is registered already (" + joined() + ")");
  registry().push_back(std::move(info));
}

std::unique_ptr<ControlMethod> makeMethod(const ControllerParams& params, const std::string& where) {
  return findMethod(params.method, where).make(params);
}

}  // namespace lexdyn::control
