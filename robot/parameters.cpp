#include "robot/parameters.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>
#include <sstream>

#include "robot/errors.hpp"

namespace flexirob::robot {

ParameterSet::ParameterSet(std::span<const ParameterDeclaration> declarations)
    : declarations_(declarations.begin(), declarations.end()) {
  for (const auto& declaration : declarations_) values_[declaration.name] = declaration.default_value;
}

const ParameterDeclaration& ParameterSet::find(const std::string& name) const {
  for (const auto& declaration : declarations_) {
    if (name == declaration.name) return declaration;
  }
  throw InputError("unknown parameter '" + name + "'");
}

double ParameterSet::get(const std::string& name) const {
  find(name);
  return values_.at(name);
}

void ParameterSet::set(const std::string& name, double value) {
  const ParameterDeclaration& declaration = find(name);
  if (!std::isfinite(value) || value < declaration.min_value || value > declaration.max_value) {
    std::ostringstream message;
    message << "parameter '" << name << "': expected a value in [" << declaration.min_value << ", "
            << declaration.max_value << "]" << (declaration.unit[0] == '\0' ? "" : " ") << declaration.unit << ", got " << value;
    throw InputError(message.str());
  }
  values_[name] = value;
}

int ParameterSet::applyOverrides(const std::map<std::string, double>& overrides, const std::string& origin) {
  int applied = 0;
  for (const auto& [name, value] : overrides) {
    if (values_.count(name) == 0) continue;
    try {
      set(name, value);
    } catch (const InputError& e) {
      if (origin.empty()) throw;
      throw InputError(origin + ": " + e.what());
    }
    ++applied;
  }
  return applied;
}

std::string undeclaredParameterReason(const std::string& name, std::span<const ParameterDeclaration> known) {
  std::vector<std::string> declared;
  for (const auto& declaration : known) {
    if (name == declaration.name) return "";
    declared.emplace_back(declaration.name);
  }
  const std::string reason = "unknown parameter '" + name + "'";
  // A slip of a few letters (a doubled, dropped or swapped letter, a wrong separator) is taken as meant.
  if (const std::string meant = closestName(name, declared); !meant.empty()) return reason + " (did you mean '" + meant + "'?)";
  // Otherwise the names there are, by component: "sim.{substeps, gravity}".
  std::string names;
  std::string component;
  for (const auto& declaration : known) {
    const std::string full = declaration.name;
    const std::size_t dot = full.find('.');
    const std::string prefix = dot == std::string::npos ? "" : full.substr(0, dot + 1);
    if (prefix != component || names.empty()) {
      if (!names.empty()) names += component.empty() ? ", " : "}, ";
      names += prefix.empty() ? "" : prefix + "{";
      component = prefix;
    } else {
      names += ", ";
    }
    names += full.substr(prefix.size());
  }
  if (!component.empty()) names += "}";
  return reason + "; the parameters are " + names;
}

}  // namespace flexirob::robot
