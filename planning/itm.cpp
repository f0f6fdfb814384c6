#include "planning/itm.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace flexirob::planning {
namespace {

constexpr double kMaxCoordinate = 1e5;  // m; positions beyond are refused as bad input
constexpr int kMaxJoints = 64;

std::string number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

}  // namespace

void ItmParameters::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("ITM parameters: " + what); };
  if (!(e_max >= 1e-4 && e_max <= 1e3)) fail("expected 1e-4 <= e_max <= 1000, got " + number(e_max));
  if (delta < 0 || delta > 32) fail("expected 0 <= delta <= 32, got " + std::to_string(delta));
  if (!(d_theta_max > 0.0)) fail("expected d_theta_max > 0, got " + number(d_theta_max));
  if (!(d_c_max >= 0.0 && d_c_max <= 1e3)) fail("expected 0 <= d_c_max <= 1000, got " + number(d_c_max));
  if (!(eta >= 0.0 && eta <= 1.0)) fail("expected 0 <= eta <= 1, got " + number(eta));
  if (!(alpha >= 0.0 && alpha < 1.0)) fail("expected 0 <= alpha < 1, got " + number(alpha));
  if (variant == ItmVariant::kHybrid && eta != 0.0) fail("the hybrid ITM does not adapt nodes (Alg. 7.2): eta must be 0");
}

Itm::Itm(const ItmParameters& parameters, int joint_count)
    : parameters_(parameters),
      metric_(parameters.task_space, parameters.alpha),
      joint_count_(joint_count),
      task_size_(storedSize(parameters.task_space)),
      grid_(parameters.e_max),
      sample_grid_(parameters.e_max) {
  parameters_.validate();
  if (joint_count < 1 || joint_count > kMaxJoints) {
    throw std::invalid_argument("ITM: expected 1 to " + std::to_string(kMaxJoints) + " joints, got " +
                                std::to_string(joint_count));
  }
  scratch_point_.resize(static_cast<std::size_t>(task_size_));
}

// ---------------------------------------------------------------------------------------------
// Graph access

std::vector<int> Itm::nodeIds() const {
  std::vector<int> ids;
  ids.reserve(static_cast<std::size_t>(node_count_));
  for (int id = 0; id < slotCount(); ++id) {
    if (alive_[static_cast<std::size_t>(id)] != 0) ids.push_back(id);
  }
  return ids;
}

Eigen::Map<const Eigen::VectorXd> Itm::prototype(int id) const {
  if (!isNode(id)) throw std::out_of_range("ITM: no node " + std::to_string(id));
  return Eigen::Map<const Eigen::VectorXd>(omega(id), task_size_);
}

Eigen::Map<const Eigen::VectorXd> Itm::joints(int id) const {
  if (!isNode(id)) throw std::out_of_range("ITM: no node " + std::to_string(id));
  return Eigen::Map<const Eigen::VectorXd>(q(id), joint_count_);
}

bool Itm::hasEdge(int a, int b) const {
  if (!isNode(a) || !isNode(b)) return false;
  const auto& list = adjacency_[static_cast<std::size_t>(a)];
  return std::find(list.begin(), list.end(), b) != list.end();
}

double Itm::distance(int a, int b) const { return metric_.distance(omega(a), omega(b)); }

double Itm::distanceTo(int id, const Eigen::VectorXd& xi) const {
  if (xi.size() != task_size_) throw std::invalid_argument("ITM: point of wrong size");
  return metric_.distance(omega(id), xi.data());
}

double Itm::jointDistance(const double* qa, const double* qb) const {
  double sum = 0.0;
  for (int i = 0; i < joint_count_; ++i) sum += (qa[i] - qb[i]) * (qa[i] - qb[i]);
  return std::sqrt(sum);
}

double Itm::jointDistance(int a, int b) const { return jointDistance(q(a), q(b)); }

// ---------------------------------------------------------------------------------------------
// Spatial queries: growing boxes in the voxel grid. A node with D_xi < d has a translational
// distance below d / translationFactor(), so a box of that half-width holds every candidate.

Itm::Nearest Itm::nearestTwo(const double* xi) const {
  Nearest best;
  if (node_count_ == 0) return best;
  const auto consider = [&](int id) {
    const double d = metric_.distance(xi, omega(id));
    if (best.first < 0 || d < best.d_first) {
      best.second = best.first;
      best.d_second = best.d_first;
      best.first = id;
      best.d_first = d;
    } else if (best.second < 0 || d < best.d_second) {
      best.second = id;
      best.d_second = d;
    }
  };
  const int wanted = std::min(node_count_, 2);
  const double factor = metric_.translationFactor();
  double half_width = grid_.cellSize();
  for (;;) {
    double lo[3], hi[3];
    for (int i = 0; i < 3; ++i) {
      lo[i] = xi[i] - half_width;
      hi[i] = xi[i] + half_width;
    }
    // Far from every node (a sparse graph, a new area): scanning all nodes is cheaper.
    if (grid_.cellsInBox(lo, hi) > 2 * static_cast<std::int64_t>(node_count_) + 27) {
      best = Nearest{};
      for (int id = 0; id < slotCount(); ++id) {
        if (alive_[static_cast<std::size_t>(id)] != 0) consider(id);
      }
      return best;
    }
    best = Nearest{};
    int seen = 0;
    grid_.forEachInBox(lo, hi, [&](int id) {
      consider(id);
      ++seen;
    });
    if (seen == node_count_) return best;
    const int found = best.second >= 0 ? 2 : (best.first >= 0 ? 1 : 0);
    if (found >= wanted) {
      const double d_needed = wanted == 2 ? best.d_second : best.d_first;
      if (d_needed <= factor * half_width) return best;
    }
    half_width *= 2.0;
  }
}

int Itm::nearestNode(const Eigen::VectorXd& xi, bool position_only) const {
  if (position_only) {
    if (xi.size() < 3) throw std::invalid_argument("ITM: expected a position of 3 numbers");
    if (task_size_ == 3) return nearestTwo(xi.data()).first;
    // Translational distance only: the pose metric's lower bound, searched by brute force over
    // the few candidates of a growing box.
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    const auto consider = [&](int id) {
      const double* w = omega(id);
      const double d = std::sqrt((w[0] - xi[0]) * (w[0] - xi[0]) + (w[1] - xi[1]) * (w[1] - xi[1]) +
                                 (w[2] - xi[2]) * (w[2] - xi[2]));
      if (d < best_d) {
        best_d = d;
        best = id;
      }
    };
    double half_width = grid_.cellSize();
    while (node_count_ > 0) {
      double lo[3], hi[3];
      for (int i = 0; i < 3; ++i) {
        lo[i] = xi[i] - half_width;
        hi[i] = xi[i] + half_width;
      }
      if (grid_.cellsInBox(lo, hi) > 2 * static_cast<std::int64_t>(node_count_) + 27) {
        for (int id = 0; id < slotCount(); ++id) {
          if (alive_[static_cast<std::size_t>(id)] != 0) consider(id);
        }
        return best;
      }
      int seen = 0;
      grid_.forEachInBox(lo, hi, [&](int id) {
        consider(id);
        ++seen;
      });
      if (seen == node_count_ || (best >= 0 && best_d <= half_width)) return best;
      half_width *= 2.0;
    }
    return -1;
  }
  if (xi.size() != task_size_) {
    throw std::invalid_argument("ITM: expected a task-space point of " + std::to_string(task_size_) + " numbers, got " +
                                std::to_string(xi.size()));
  }
  return nearestTwo(xi.data()).first;
}

std::vector<int> Itm::nodesWithin(const Eigen::VectorXd& xi, double radius, bool position_only) const {
  if (position_only ? xi.size() < 3 : xi.size() != task_size_) throw std::invalid_argument("ITM: point of wrong size");
  std::vector<int> result;
  const double half_width = position_only ? radius : radius / metric_.translationFactor();
  double lo[3], hi[3];
  for (int i = 0; i < 3; ++i) {
    lo[i] = xi[i] - half_width;
    hi[i] = xi[i] + half_width;
  }
  const auto consider = [&](int id) {
    const double* w = omega(id);
    const double d = position_only ? std::sqrt((w[0] - xi[0]) * (w[0] - xi[0]) + (w[1] - xi[1]) * (w[1] - xi[1]) +
                                               (w[2] - xi[2]) * (w[2] - xi[2]))
                                   : metric_.distance(xi.data(), w);
    if (d < radius) result.push_back(id);
  };
  if (grid_.cellsInBox(lo, hi) > 2 * static_cast<std::int64_t>(node_count_) + 27) {
    for (int id = 0; id < slotCount(); ++id) {
      if (alive_[static_cast<std::size_t>(id)] != 0) consider(id);
    }
  } else {
    grid_.forEachInBox(lo, hi, consider);
  }
  return result;
}

// ---------------------------------------------------------------------------------------------
// Graph edits

int Itm::createNode(const double* w, const double* q_new, bool bootstrapped) {
  int id;
  if (!free_slots_.empty()) {
    id = free_slots_.back();
    free_slots_.pop_back();
  } else {
    id = slotCount();
    omegas_.resize(omegas_.size() + static_cast<std::size_t>(task_size_));
    configurations_.resize(configurations_.size() + static_cast<std::size_t>(joint_count_));
    adjacency_.emplace_back();
    alive_.push_back(0);
    bootstrapped_.push_back(0);
  }
  const auto index = static_cast<std::size_t>(id);
  std::copy(w, w + task_size_, omegas_.begin() + static_cast<std::ptrdiff_t>(index * static_cast<std::size_t>(task_size_)));
  std::copy(q_new, q_new + joint_count_,
            configurations_.begin() + static_cast<std::ptrdiff_t>(index * static_cast<std::size_t>(joint_count_)));
  adjacency_[index].clear();
  alive_[index] = 1;
  bootstrapped_[index] = bootstrapped ? 1 : 0;
  grid_.insert(id, omega(id));
  ++node_count_;
  return id;
}

void Itm::connect(int a, int b) {
  adjacency_[static_cast<std::size_t>(a)].push_back(b);
  adjacency_[static_cast<std::size_t>(b)].push_back(a);
  ++edge_count_;
}

void Itm::disconnect(int a, int b) {
  const auto erase = [](std::vector<int>& list, int value) {
    const auto it = std::find(list.begin(), list.end(), value);
    *it = list.back();
    list.pop_back();
  };
  erase(adjacency_[static_cast<std::size_t>(a)], b);
  erase(adjacency_[static_cast<std::size_t>(b)], a);
  --edge_count_;
}

void Itm::removeNode(int id, InsertReport& report) {
  const std::vector<int> neighbours = adjacency_[static_cast<std::size_t>(id)];
  for (int c : neighbours) {
    disconnect(id, c);
    maybe_isolated_.push_back(c);
    ++report.edges_removed;
  }
  grid_.remove(id, omega(id));
  alive_[static_cast<std::size_t>(id)] = 0;
  free_slots_.push_back(id);
  --node_count_;
  ++report.nodes_removed;
}

void Itm::moveNode(int id, const double* new_omega) {
  grid_.remove(id, omega(id));
  std::copy(new_omega, new_omega + task_size_,
            omegas_.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(id) * static_cast<std::size_t>(task_size_)));
  grid_.insert(id, omega(id));
}

int Itm::addNode(const Eigen::VectorXd& w, const Eigen::VectorXd& q_new, bool bootstrapped) {
  if (w.size() != task_size_ || q_new.size() != joint_count_) {
    throw std::invalid_argument("ITM: node of wrong size (expected " + std::to_string(task_size_) + " + " +
                                std::to_string(joint_count_) + " numbers)");
  }
  if (!w.allFinite() || !q_new.allFinite()) throw std::invalid_argument("ITM: node with non-finite values");
  if (w.head<3>().cwiseAbs().maxCoeff() > kMaxCoordinate) throw std::invalid_argument("ITM: node position beyond 100 km");
  return createNode(w.data(), q_new.data(), bootstrapped);
}

void Itm::addEdge(int a, int b) {
  if (!isNode(a) || !isNode(b)) throw std::invalid_argument("ITM: edge between unknown nodes");
  if (a == b) throw std::invalid_argument("ITM: self-edge at node " + std::to_string(a));
  if (hasEdge(a, b)) throw std::invalid_argument("ITM: duplicate edge");
  connect(a, b);
}

void Itm::restoreSamples(std::vector<double> kept_positions, std::int64_t real_samples, std::int64_t bootstrap_samples) {
  if (kept_positions.size() % 3 != 0) throw std::invalid_argument("ITM: sample positions must come in triples");
  sample_grid_.clear();
  kept_samples_ = std::move(kept_positions);
  for (std::size_t i = 0; i < kept_samples_.size(); i += 3) sample_grid_.insert(static_cast<int>(i / 3), &kept_samples_[i]);
  real_samples_ = real_samples;
  bootstrap_samples_ = bootstrap_samples;
}

// ---------------------------------------------------------------------------------------------
// Learning

InsertReport Itm::insert(const Eigen::VectorXd& xi_in, const Eigen::VectorXd& q_in) {
  if (xi_in.size() != task_size_) {
    throw std::invalid_argument("ITM: expected a task-space sample of " + std::to_string(task_size_) + " numbers, got " +
                                std::to_string(xi_in.size()));
  }
  if (q_in.size() != joint_count_) {
    throw std::invalid_argument("ITM: expected " + std::to_string(joint_count_) + " joint values, got " +
                                std::to_string(q_in.size()));
  }
  if (!xi_in.allFinite() || !q_in.allFinite()) throw std::invalid_argument("ITM: sample with non-finite values");
  if (xi_in.head<3>().cwiseAbs().maxCoeff() > kMaxCoordinate) throw std::invalid_argument("ITM: sample position beyond 100 km");
  Eigen::VectorXd xi = xi_in;
  if (task_size_ == 7) {
    const double norm = xi.tail<4>().norm();
    if (!(norm > 1e-9)) throw std::invalid_argument("ITM: sample quaternion of zero length");
    xi.tail<4>() /= norm;
  }

  InsertReport report;
  ++real_samples_;
  keepSample(xi.data());
  const int r = processStimulus(xi.data(), q_in.data(), false, report);
  report.created = r;
  if (r >= 0 && parameters_.variant == ItmVariant::kHybrid) bootstrap(r, report);
  return report;
}

void Itm::keepSample(const double* xi) {
  const std::size_t k = kept_samples_.size();
  if (k >= 3) {
    const double dx = xi[0] - kept_samples_[k - 3], dy = xi[1] - kept_samples_[k - 2], dz = xi[2] - kept_samples_[k - 1];
    if (dx * dx + dy * dy + dz * dz <= sampleResolution() * sampleResolution()) return;
  }
  kept_samples_.insert(kept_samples_.end(), xi, xi + 3);
  sample_grid_.insert(static_cast<int>(k / 3), xi);
}

int Itm::processStimulus(const double* xi, const double* q_xi, bool bootstrapped, InsertReport& report) {
  const bool hybrid = parameters_.variant == ItmVariant::kHybrid;
  const double e_max = parameters_.e_max;
  const auto jointsCompatible = [&](const double* qa, const double* qb) {
    return !hybrid || jointDistance(qa, qb) < parameters_.d_theta_max;  // Sect. 7.3.1
  };

  // 1) Matching.
  const Nearest match = nearestTwo(xi);
  if (!bootstrapped) {
    report.winner = match.first;
    report.second = match.second;
  }
  if (match.first < 0) return createNode(xi, q_xi, bootstrapped);  // the first stimulus
  const int n = match.first;
  const int s = match.second;

  if (s < 0) {
    // A single node: the second node appears once a stimulus lies farther than e_max (the map
    // starts with two connected nodes, Sect. 7.2).
    if (match.d_first <= e_max) return -1;
    const int r = createNode(xi, q_xi, bootstrapped);
    if (jointsCompatible(q(r), q(n))) {
      connect(r, n);
      ++report.edges_added;
    }
    return r;
  }

  if (!hybrid) {
    // 2) Adapt the winner (Alg. 7.1); a pose quaternion is renormalized after the step.
    if (parameters_.eta > 0.0) {
      double* moved = scratch_point_.data();
      for (int i = 0; i < task_size_; ++i) moved[i] = omega(n)[i] + parameters_.eta * (xi[i] - omega(n)[i]);
      if (task_size_ == 7) {
        const double norm = std::sqrt(moved[3] * moved[3] + moved[4] * moved[4] + moved[5] * moved[5] + moved[6] * moved[6]);
        for (int i = 3; i < 7; ++i) moved[i] /= norm;
      }
      moveNode(n, moved);
    }
    // 3) Edge between the winners; remove the edges (n, c) whose Thales sphere holds s.
    if (!hasEdge(n, s)) {
      connect(n, s);
      ++report.edges_added;
    }
    const std::vector<int> neighbours = adjacency_[static_cast<std::size_t>(n)];
    for (int c : neighbours) {
      if (c == s) continue;
      if (metric_.thalesProduct(omega(n), omega(c), omega(s)) < 0.0) {
        disconnect(n, c);
        ++report.edges_removed;
        maybe_isolated_.push_back(c);
      }
    }
    // Delete unconnected nodes (n keeps its edge to s).
    for (int c : maybe_isolated_) {
      if (isNode(c) && adjacency_[static_cast<std::size_t>(c)].empty()) removeNode(c, report);
    }
    maybe_isolated_.clear();
    // 4) New node outside the Thales sphere over n, s and beyond e_max; drop s if too close.
    int r = -1;
    if (metric_.thalesProduct(omega(n), omega(s), xi) > 0.0 && metric_.distance(xi, omega(n)) > e_max) {
      r = createNode(xi, q_xi, bootstrapped);
      connect(r, n);
      ++report.edges_added;
    }
    if (metric_.distance(omega(n), omega(s)) < 0.5 * e_max) removeNode(s, report);
    return r;
  }

  // Hybrid ITM, Alg. 7.2.
  // 2) Edge between the winners when their joint configurations are close.
  if (!hasEdge(n, s) && jointsCompatible(q(n), q(s))) {
    connect(n, s);
    ++report.edges_added;
  }
  // 3), 4) New node outside the Thales sphere over n, s and farther than e_max, joined to n
  // under the joint criterion.
  if (metric_.thalesProduct(omega(n), omega(s), xi) > 0.0 && match.d_first > e_max) {
    const int r = createNode(xi, q_xi, bootstrapped);
    if (jointsCompatible(q(r), q(n))) {
      connect(r, n);
      ++report.edges_added;
    }
    return r;
  }
  return -1;
}

void Itm::collectNeighbourhood(int r, int delta, std::vector<int>& out) {
  out.clear();
  if (visit_stamp_.size() < static_cast<std::size_t>(slotCount())) visit_stamp_.resize(static_cast<std::size_t>(slotCount()), 0);
  if (++stamp_ == 0) {
    std::fill(visit_stamp_.begin(), visit_stamp_.end(), 0);
    stamp_ = 1;
  }
  visit_stamp_[static_cast<std::size_t>(r)] = stamp_;
  frontier_.assign(1, r);
  for (int depth = 0; depth < delta && !frontier_.empty(); ++depth) {
    next_frontier_.clear();
    for (int node : frontier_) {
      for (int c : adjacency_[static_cast<std::size_t>(node)]) {
        if (visit_stamp_[static_cast<std::size_t>(c)] == stamp_) continue;
        visit_stamp_[static_cast<std::size_t>(c)] = stamp_;
        next_frontier_.push_back(c);
        out.push_back(c);
      }
    }
    std::swap(frontier_, next_frontier_);
  }
}

void Itm::bootstrap(int r, InsertReport& report) {
  // Copies: creating nodes may reallocate the node storage.
  const std::vector<double> omega_r(omega(r), omega(r) + task_size_);
  const std::vector<double> q_r(q(r), q(r) + joint_count_);
  std::vector<double> sample(static_cast<std::size_t>(task_size_));
  const auto trainWithMidpoint = [&](int c) {
    metric_.midpoint(omega(c), omega_r.data(), sample.data());  // Eq. 7.2
    ++report.bootstrap_samples;
    ++bootstrap_samples_;
    if (processStimulus(sample.data(), q_r.data(), true, report) >= 0) ++report.bootstrap_nodes;
  };

  // 5) Local bootstrapping towards the delta-neighbourhood, only for nodes closer than 3 e_max.
  if (parameters_.delta > 0) {
    collectNeighbourhood(r, parameters_.delta, neighbourhood_);
    const std::vector<int> local = neighbourhood_;
    for (int c : local) {
      if (metric_.distance(omega_r.data(), omega(c)) < 3.0 * parameters_.e_max) trainWithMidpoint(c);
    }
  }

  // 6) Global bootstrapping within d_Cmax outside the delta-neighbourhood (as it is now), under
  // the joint criterion (Eq. 7.3-7.4).
  if (parameters_.d_c_max > 0.0) {
    candidates_ = nodesWithin(Eigen::Map<const Eigen::VectorXd>(omega_r.data(), task_size_), parameters_.d_c_max);
    collectNeighbourhood(r, parameters_.delta, neighbourhood_);
    const std::vector<int> global = candidates_;
    const std::uint32_t stamp = stamp_;
    for (int c : global) {
      if (c == r) continue;
      if (static_cast<std::size_t>(c) < visit_stamp_.size() && visit_stamp_[static_cast<std::size_t>(c)] == stamp) continue;
      if (jointDistance(q_r.data(), q(c)) < parameters_.d_theta_max) trainWithMidpoint(c);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Statistics (Tab. 7.1)

ItmStatistics Itm::statistics() const {
  ItmStatistics stats;
  stats.nodes = node_count_;
  stats.edges = edge_count_;
  stats.real_samples = real_samples_;
  stats.bootstrap_samples = bootstrap_samples_;
  stats.mean_valence = node_count_ > 0 ? 2.0 * edge_count_ / node_count_ : 0.0;

  // Connected components by union-find over the edges.
  std::vector<int> parent(static_cast<std::size_t>(slotCount()));
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](int x) {
    while (parent[static_cast<std::size_t>(x)] != x) {
      parent[static_cast<std::size_t>(x)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
      x = parent[static_cast<std::size_t>(x)];
    }
    return x;
  };
  int merges = 0;
  double error_sum = 0.0;
  stats.bootstrap_error_max = 0.0;
  for (int id = 0; id < slotCount(); ++id) {
    if (alive_[static_cast<std::size_t>(id)] == 0) continue;
    const auto& list = adjacency_[static_cast<std::size_t>(id)];
    stats.max_valence = std::max(stats.max_valence, static_cast<int>(list.size()));
    for (int c : list) {
      const int a = root(id), b = root(c);
      if (a != b) {
        parent[static_cast<std::size_t>(a)] = b;
        ++merges;
      }
    }
    if (bootstrapped_[static_cast<std::size_t>(id)] == 0) continue;
    // Distance of this bootstrapped node to the nearest kept real sample.
    ++stats.bootstrapped_nodes;
    const double* p = omega(id);
    double best = std::numeric_limits<double>::infinity();
    double half_width = sample_grid_.cellSize();
    const auto samples = static_cast<std::int64_t>(kept_samples_.size() / 3);
    while (samples > 0) {
      double lo[3], hi[3];
      for (int i = 0; i < 3; ++i) {
        lo[i] = p[i] - half_width;
        hi[i] = p[i] + half_width;
      }
      const bool brute = sample_grid_.cellsInBox(lo, hi) > 2 * samples + 27;
      std::int64_t seen = 0;
      const auto consider = [&](int k) {
        const double* x = &kept_samples_[static_cast<std::size_t>(k) * 3];
        best = std::min(best, std::sqrt((x[0] - p[0]) * (x[0] - p[0]) + (x[1] - p[1]) * (x[1] - p[1]) +
                                        (x[2] - p[2]) * (x[2] - p[2])));
        ++seen;
      };
      if (brute) {
        for (std::int64_t k = 0; k < samples; ++k) consider(static_cast<int>(k));
      } else {
        sample_grid_.forEachInBox(lo, hi, consider);
      }
      if (brute || seen == samples || best <= half_width) break;
      half_width *= 2.0;
    }
    stats.bootstrap_error_max = std::max(stats.bootstrap_error_max, best);
    error_sum += best;
  }
  stats.components = node_count_ - merges;
  if (stats.bootstrapped_nodes > 0) {
    stats.bootstrap_error_mean = error_sum / stats.bootstrapped_nodes;
  } else {
    stats.bootstrap_error_max = stats.bootstrap_error_mean = std::numeric_limits<double>::quiet_NaN();
  }
  return stats;
}

}  // namespace flexirob::planning
