#pragma once
// A hashed voxel grid over 3-D positions: the ITM's spatial index. Cells of a fixed edge length
// (about e_max) hold the ids of the nodes whose position falls in them, so that nearest-node and
// radius queries touch a few cells whatever the size of the graph, and nodes can be inserted,
// moved and removed in O(1).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace flexirob::planning {

class SpatialHashGrid {
 public:
  struct Cell {
    std::int32_t x = 0, y = 0, z = 0;
    bool operator==(const Cell&) const = default;
  };

  /// cell_size [m] > 0. Positions must satisfy |p_i| / cell_size < 2^30.
  explicit SpatialHashGrid(double cell_size);

  double cellSize() const { return cell_size_; }
  Cell cellOf(const double* p) const;

  void insert(int id, const double* p);
  /// Removes id, which must have been inserted at a position in the same cell as p.
  void remove(int id, const double* p);
  void clear();

  /// Ids stored in one cell (nullptr when the cell is empty or unknown).
  const std::vector<int>* find(const Cell& cell) const;

  /// Bounding box (in cells) of every cell that ever held an id; empty() when none.
  bool empty() const { return occupied_cells_ == 0; }
  const Cell& minCell() const { return min_cell_; }
  const Cell& maxCell() const { return max_cell_; }

  /// Calls visit(id) for every id in the cells overlapping the axis-aligned box [lo, hi].
  template <class Visit>
  void forEachInBox(const double* lo, const double* hi, Visit&& visit) const {
    if (empty()) return;
    const Cell a = cellOf(lo);
    const Cell b = cellOf(hi);
    const std::int32_t x0 = std::max(a.x, min_cell_.x), x1 = std::min(b.x, max_cell_.x);
    const std::int32_t y0 = std::max(a.y, min_cell_.y), y1 = std::min(b.y, max_cell_.y);
    const std::int32_t z0 = std::max(a.z, min_cell_.z), z1 = std::min(b.z, max_cell_.z);
    for (std::int32_t x = x0; x <= x1; ++x) {
      for (std::int32_t y = y0; y <= y1; ++y) {
        for (std::int32_t z = z0; z <= z1; ++z) {
          if (const auto* ids = find(Cell{x, y, z})) {
            for (int id : *ids) visit(id);
          }
        }
      }
    }
  }

  /// Number of cells in the box [lo, hi] clipped to the occupied bounding box: what
  /// forEachInBox would probe.
  std::int64_t cellsInBox(const double* lo, const double* hi) const;

 private:
  std::size_t slotOf(const Cell& cell) const;
  void grow();

  double cell_size_;
  double inverse_cell_size_;
  // Open addressing with linear probing; cells are never removed from the table (an emptied
  // cell keeps its slot), so no tombstones are needed.
  std::vector<Cell> keys_;
  std::vector<std::int32_t> bucket_of_slot_;  // -1 = free slot
  std::vector<std::vector<int>> buckets_;
  std::size_t occupied_cells_ = 0;
  Cell min_cell_, max_cell_;
};

}  // namespace flexirob::planning
