#pragma once
// Declared parameters: every tunable value of the control stack has a name, a default, a range
// and a unit, so that the GUI can list them and scenes can override them by name (DESIGN §2).
#include <map>
#include <span>
#include <string>
#include <vector>

namespace flexirob::robot {

struct ParameterDeclaration {
  const char* name;         ///< unique, dotted ("hierarchical.kappa_x")
  double default_value;
  double min_value;         ///< inclusive
  double max_value;         ///< inclusive
  const char* unit;         ///< SI unit ("1/s", "Nm/rad", "" for ratios)
  const char* description;  ///< one line for tooltips
};

/// Values of a set of declared parameters. Construction gives the defaults; set() checks the
/// name and range and throws InputError("parameter 'x': expected a value in [a, b], got c").
class ParameterSet {
 public:
  explicit ParameterSet(std::span<const ParameterDeclaration> declarations);

  double get(const std::string& name) const;
  bool has(const std::string& name) const { return values_.count(name) != 0; }
  void set(const std::string& name, double value);
  /// Applies the entries of `overrides` whose names are declared here; other names are left to
  /// the other components (a scene overrides parameters of several at once; the scene reader
  /// refuses names none declares). Returns how many applied.
  /// A value out of range throws InputError, prefixed with `origin` (a scene file) if given.
  int applyOverrides(const std::map<std::string, double>& overrides, const std::string& origin = "");
  const std::vector<ParameterDeclaration>& declarations() const { return declarations_; }

 private:
  const ParameterDeclaration& find(const std::string& name) const;
  std::vector<ParameterDeclaration> declarations_;
  std::map<std::string, double> values_;
};

/// Every parameter a scene's `parameters` may set: the hierarchical controller's, the limiter's,
/// the simulation's (robot/sim/reach.hpp reachParameters()) and interaction.* (the recording
/// and teach-in controllers). The triggers' are the workflow's options, not a scene's.
std::vector<ParameterDeclaration> sceneTunableParameters();

/// "" when `name` is declared in `known`; otherwise why not, naming the closest declared name
/// when a slip of a few letters explains it ("did you mean 'hierarchical.kappa_q'?") and the
/// names there are.
std::string undeclaredParameterReason(const std::string& name, std::span<const ParameterDeclaration> known);

}  // namespace flexirob::robot
