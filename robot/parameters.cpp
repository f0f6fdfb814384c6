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
  for (const auto& declaration : known) {
    if (name == declaration.name) return "";
  }
  // Names are "component.name": a slip is looked for among the named component's parameters,
  // where its prefix is one (the shared prefix would pay for a wholly different suffix), and
  // among all names otherwise ("sim_gravity").
  const auto componentOf = [](const std::string& full) {
    const std::size_t dot = full.find('.');
    return dot == std::string::npos ? std::string() : full.substr(0, dot + 1);
  };
  const std::string component = componentOf(name);
  std::vector<std::string> suffixes;
  std::vector<std::string> all;
  std::string listed;  // the component's names, or all of them by component: "sim.{substeps, gravity}"
  std::string listing;
  for (const auto& declaration : known) {
    const std::string full = declaration.name;
    const std::string prefix = componentOf(full);
    all.push_back(full);
    if (!component.empty() && prefix == component) suffixes.push_back(full.substr(prefix.size()));
  }
  std::string meant;
  if (!suffixes.empty()) {
    const std::string suffix = name.substr(component.size());
    const std::string guess = closestName(suffix, suffixes, std::max<std::size_t>(1, suffix.size() / 3));
    if (!guess.empty()) meant = component + guess;
    for (const std::string& s : suffixes) listed += (listed.empty() ? "" : ", ") + s;
    listed = component + "{" + listed + "}";
  } else {
    meant = closestName(name, all, std::max<std::size_t>(1, name.size() / 4));
    for (const auto& declaration : known) {
      const std::string full = declaration.name;
      const std::string prefix = componentOf(full);
      if (prefix != listing || listed.empty()) {
        if (!listed.empty()) listed += listing.empty() ? ", " : "}, ";
        listed += prefix.empty() ? "" : prefix + "{";
        listing = prefix;
      } else {
        listed += ", ";
      }
      listed += full.substr(prefix.size());
    }
    if (!listing.empty()) listed += "}";
  }
  return "unknown parameter '" + name + "'" + (meant.empty() ? "" : " (did you mean '" + meant + "'?)") + "; the parameters are " + listed;
}

}  // namespace flexirob::robot
