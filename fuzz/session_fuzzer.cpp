// Fuzz target: session databases (app/session_reader.hpp). A file that is not a readable
// FlexIRob session must be refused with an InputError at open, or with an SqliteError (the
// reader's documented error for damaged rows and pages) when a table is read; SQLite itself
// guards the page format, our code the header, schema, version and row checks, and the
// teaching read back from the rows (app/session_teaching.hpp) with the ITM snapshot inside.
#include <cstddef>
#include <cstdint>

#include "app/session_reader.hpp"
#include "app/session_schema.hpp"
#include "app/session_teaching.hpp"
#include "fuzz/fuzz_support.hpp"
#include "robot/errors.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static flexirob::fuzz::InputFile file(".session");
  const auto& path = file.write(data, size);
  try {
    const flexirob::app::SessionReader reader(path);
    (void)reader.metadata();
    (void)reader.states(reader.startTime(), reader.endTime(), 1);
    (void)reader.stateAt(reader.startTime());
    (void)reader.stages();
    (void)reader.signals();
    (void)reader.collisions();
    (void)reader.areas();
    (void)reader.samples();
    (void)reader.sampleCounts();
    (void)reader.models();
    (void)reader.itmSnapshots();
    (void)reader.itmSnapshotCount();
    // What eval, render, review and the study read: takes per area and the last graph, decoded.
    (void)flexirob::app::readRecordedTeaching(reader);
  } catch (const flexirob::InputError&) {
  } catch (const flexirob::app::SqliteError&) {
  }
  return 0;
}
