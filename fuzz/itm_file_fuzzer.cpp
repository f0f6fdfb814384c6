// Fuzz target: ITM graph files (planning/itm_file.hpp). Anything malformed must end in an
// ItmFileError; an accepted graph must satisfy the graph invariants and save/load identically.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_support.hpp"
#include "planning/itm_file.hpp"

namespace {

void checkGraph(const std::string& bytes) {
  static flexirob::fuzz::InputFile file(".itm");
  const auto& path = file.write(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  try {
    const flexirob::planning::Itm graph = flexirob::planning::loadItm(path);
    int directed_edges = 0;
    for (const int id : graph.nodeIds()) {
      if (!graph.prototype(id).allFinite() || !graph.joints(id).allFinite()) flexirob::fuzz::invariantBroken("non-finite node");
      for (const int other : graph.neighbors(id)) {
        if (other == id) flexirob::fuzz::invariantBroken("self edge");
        if (!graph.isNode(other)) flexirob::fuzz::invariantBroken("edge to a missing node");
        if (!graph.hasEdge(other, id)) flexirob::fuzz::invariantBroken("directed edge");
        ++directed_edges;
      }
    }
    if (directed_edges != 2 * graph.edgeCount()) flexirob::fuzz::invariantBroken("edge count != adjacency");
    if (static_cast<int>(graph.nodeIds().size()) != graph.nodeCount()) flexirob::fuzz::invariantBroken("node count");
  } catch (const flexirob::planning::ItmFileError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  checkGraph(bytes);
  checkGraph(flexirob::fuzz::withValidItmChecksum(bytes));
  return 0;
}
