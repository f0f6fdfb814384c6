#include "planning/spatial_grid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace flexirob::planning {
namespace {

std::size_t hashCell(const SpatialHashGrid::Cell& c) {
  // SplitMix64 finalizer over the packed coordinates: neighbouring cells spread over the table.
  std::uint64_t h = static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.x)) * 0x9E3779B97F4A7C15ULL;
  h ^= static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.y)) * 0xC2B2AE3D27D4EB4FULL;
  h ^= static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.z)) * 0x165667B19E3779F9ULL;
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBULL;
  h ^= h >> 31;
  return static_cast<std::size_t>(h);
}

constexpr double kMaxCellIndex = 1073741824.0;  // 2^30

}  // namespace

SpatialHashGrid::SpatialHashGrid(double cell_size) : cell_size_(cell_size), inverse_cell_size_(1.0 / cell_size) {
  if (!(cell_size > 0.0) || !std::isfinite(cell_size)) {
    throw std::invalid_argument("spatial grid: expected a positive cell size, got " + std::to_string(cell_size));
  }
  clear();
}

void SpatialHashGrid::clear() {
  keys_.assign(64, Cell{});
  bucket_of_slot_.assign(64, -1);
  buckets_.clear();
  occupied_cells_ = 0;
  min_cell_ = Cell{};
  max_cell_ = Cell{};
}

SpatialHashGrid::Cell SpatialHashGrid::cellOf(const double* p) const {
  Cell cell;
  std::int32_t* out[3] = {&cell.x, &cell.y, &cell.z};
  for (int i = 0; i < 3; ++i) {
    const double index = std::floor(p[i] * inverse_cell_size_);
    // Queries (boxes around a point) may reach past the admitted range: clamping keeps them
    // inside int32 and still covers every stored cell.
    *out[i] = static_cast<std::int32_t>(std::clamp(index, -kMaxCellIndex, kMaxCellIndex));
  }
  return cell;
}

std::size_t SpatialHashGrid::slotOf(const Cell& cell) const {
  const std::size_t mask = keys_.size() - 1;
  std::size_t slot = hashCell(cell) & mask;
  while (bucket_of_slot_[slot] >= 0 && !(keys_[slot] == cell)) slot = (slot + 1) & mask;
  return slot;
}

void SpatialHashGrid::grow() {
  std::vector<Cell> old_keys = std::move(keys_);
  std::vector<std::int32_t> old_buckets = std::move(bucket_of_slot_);
  keys_.assign(old_keys.size() * 2, Cell{});
  bucket_of_slot_.assign(old_keys.size() * 2, -1);
  for (std::size_t i = 0; i < old_keys.size(); ++i) {
    if (old_buckets[i] < 0) continue;
    const std::size_t slot = slotOf(old_keys[i]);
    keys_[slot] = old_keys[i];
    bucket_of_slot_[slot] = old_buckets[i];
  }
}

const std::vector<int>* SpatialHashGrid::find(const Cell& cell) const {
  const std::size_t slot = slotOf(cell);
  const std::int32_t bucket = bucket_of_slot_[slot];
  if (bucket < 0) return nullptr;
  const auto& ids = buckets_[static_cast<std::size_t>(bucket)];
  return ids.empty() ? nullptr : &ids;
}

void SpatialHashGrid::insert(int id, const double* p) {
  for (int i = 0; i < 3; ++i) {
    if (!(std::abs(p[i]) * inverse_cell_size_ < kMaxCellIndex)) {
      throw std::invalid_argument("spatial grid: coordinate " + std::to_string(p[i]) + " m out of range");
    }
  }
  const Cell cell = cellOf(p);
  std::size_t slot = slotOf(cell);
  if (bucket_of_slot_[slot] < 0) {
    // Keep the load factor below one half so probes stay short.
    if (2 * (buckets_.size() + 1) > keys_.size()) {
      grow();
      slot = slotOf(cell);
    }
    keys_[slot] = cell;
    bucket_of_slot_[slot] = static_cast<std::int32_t>(buckets_.size());
    buckets_.emplace_back();
    if (occupied_cells_ == 0) {
      min_cell_ = max_cell_ = cell;
    } else {
      min_cell_ = {std::min(min_cell_.x, cell.x), std::min(min_cell_.y, cell.y), std::min(min_cell_.z, cell.z)};
      max_cell_ = {std::max(max_cell_.x, cell.x), std::max(max_cell_.y, cell.y), std::max(max_cell_.z, cell.z)};
    }
    ++occupied_cells_;
  }
  buckets_[static_cast<std::size_t>(bucket_of_slot_[slot])].push_back(id);
}

void SpatialHashGrid::remove(int id, const double* p) {
  const std::size_t slot = slotOf(cellOf(p));
  if (bucket_of_slot_[slot] < 0) throw std::logic_error("spatial grid: removing an id from an unknown cell");
  auto& ids = buckets_[static_cast<std::size_t>(bucket_of_slot_[slot])];
  const auto it = std::find(ids.begin(), ids.end(), id);
  if (it == ids.end()) throw std::logic_error("spatial grid: removing an id that is not in its cell");
  *it = ids.back();
  ids.pop_back();
}

std::int64_t SpatialHashGrid::cellsInBox(const double* lo, const double* hi) const {
  if (empty()) return 0;
  const Cell a = cellOf(lo);
  const Cell b = cellOf(hi);
  const auto span = [](std::int32_t from, std::int32_t to, std::int32_t min, std::int32_t max) {
    return std::max<std::int64_t>(0, static_cast<std::int64_t>(std::min(to, max)) - std::max(from, min) + 1);
  };
  return span(a.x, b.x, min_cell_.x, max_cell_.x) * span(a.y, b.y, min_cell_.y, max_cell_.y) *
         span(a.z, b.z, min_cell_.z, max_cell_.z);
}

}  // namespace flexirob::planning
