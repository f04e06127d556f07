// Random mutations of a checkpoint (issue 20): bit flips, byte changes, cuts and insertions, as a
// damaged file would carry them. Every one is refused with a stabint::Error (the checksum catches
// it) or restores a state that steps; a refused restore changes nothing. Then the same mutations
// re-signed with a matching checksum, as a file edited on purpose: they reach the field checks
// and the restore, which must keep the same promises except that an accepted wild state may
// refuse its steps. STABINT_MUTATIONS sets the count (default 10,000 of each, a fraction of a
// second; longer runs: STABINT_MUTATIONS=100000 build/tests/test_checkpoint_mutation).
#include "../fuzz/batch_checkpoint_properties.hpp"
#include "../fuzz/checkpoint_properties.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>

namespace stabint {
namespace {

namespace cp = checkpoint_properties;
namespace bp = batch_checkpoint_properties;

int mutationCount() {
  const char* n = std::getenv("STABINT_MUTATIONS");
  return n && *n ? std::atoi(n) : 10000;
}

// One to four changes of one kind each: flip a bit, set a byte, cut the tail, insert a byte.
std::string mutate(const std::string& seed, std::mt19937_64& rng) {
  std::string bytes = seed;
  const int changes = 1 + int(rng() % 4);
  for (int c = 0; c < changes && !bytes.empty(); ++c) {
    const std::size_t at = rng() % bytes.size();
    switch (rng() % 4) {
      case 0: bytes[at] = static_cast<char>(bytes[at] ^ (1 << (rng() % 8))); break;
      case 1: bytes[at] = static_cast<char>(rng() & 0xff); break;
      case 2: bytes.resize(at); break;
      default: bytes.insert(bytes.begin() + std::ptrdiff_t(at), static_cast<char>(rng() & 0xff)); break;
    }
  }
  return bytes == seed ? seed + "x" : bytes;
}

struct Tally {
  int unreadable = 0, refused = 0, restored = 0, restored_stepping = 0;
};

// `batch`: a whole batch's checkpoint (batch_checkpoint_properties.hpp), else a Simulator's.
Tally run(bool resigned, int count, bool batch = false) {
  const std::string seed = batch ? bp::seed() : cp::seed();
  std::mt19937_64 rng(resigned ? 20 : 19);
  Tally tally;
  for (int i = 0; i < count; ++i) {
    std::string bytes = mutate(seed, rng);
    if (resigned) batch ? bp::resign(bytes) : cp::resign(bytes);
    const cp::Result r = batch ? bp::check(bytes, 3) : cp::check(bytes, 3);
    EXPECT_TRUE(r.violation.empty()) << "mutation " << i << ": " << r.violation;
    switch (r.outcome) {
      case cp::Outcome::Unreadable: ++tally.unreadable; break;
      case cp::Outcome::Refused: ++tally.refused; break;
      case cp::Outcome::Restored:
        ++tally.restored;
        if (r.steps_taken > 0) ++tally.restored_stepping;
        // A damaged file that still reads is one whose change the checksum cannot see: it must
        // step (the seed's own state does).
        if (!resigned) {
          EXPECT_GT(r.steps_taken, 0) << "mutation " << i << " restored a state that refuses every step";
        }
        break;
    }
  }
  std::printf("  %s%s: %d mutations, %d unreadable, %d refused at restore, %d restored (%d of them stepping)\n",
              batch ? "batch, " : "", resigned ? "re-signed" : "as damaged", count, tally.unreadable, tally.refused,
              tally.restored, tally.restored_stepping);
  return tally;
}

TEST(CheckpointMutation, TheSeedRestoresAndSteps) {
  const cp::Result r = cp::check(cp::seed(), 3);
  EXPECT_EQ(r.outcome, cp::Outcome::Restored);
  EXPECT_EQ(r.steps_taken, 3);
}

TEST(CheckpointMutation, DamagedCheckpointsAreRefusedOrStep) {
  const Tally t = run(false, mutationCount());
  EXPECT_EQ(t.unreadable + t.refused + t.restored, mutationCount());
}

TEST(CheckpointMutation, ResignedCheckpointsKeepTheRestorePromises) {
  const Tally t = run(true, mutationCount());
  // Re-signed, the mutations reach the restore: some are refused there and some restore.
  EXPECT_GT(t.restored, 0);
}

// The same for a whole batch's checkpoint (BatchCheckpoint), a fifth as many (each builds a
// batch of two scenes).
TEST(CheckpointMutation, TheBatchSeedRestoresAndSteps) {
  const cp::Result r = bp::check(bp::seed(), 3);
  EXPECT_EQ(r.outcome, cp::Outcome::Restored);
  EXPECT_EQ(r.steps_taken, 3);
}

TEST(CheckpointMutation, DamagedBatchCheckpointsAreRefusedOrStep) {
  const int count = mutationCount() / 5;
  const Tally t = run(false, count, /*batch=*/true);
  EXPECT_EQ(t.unreadable + t.refused + t.restored, count);
}

TEST(CheckpointMutation, ResignedBatchCheckpointsKeepTheRestorePromises) {
  const Tally t = run(true, mutationCount() / 5, /*batch=*/true);
  EXPECT_GT(t.restored, 0);
}

// A batch checkpoint's time follows the 1e150 rule of every real a checkpoint holds, and a
// restore refuses a time too large for a step to advance (every scene would stay at one time for
// ever; before, 1e151 restored and every scene went inactive): re-signed seeds with the time set
// to 1e151 are unreadable (FileFormatError), to 1e20 refused by the restore (InvalidInputError
// naming restore), which changes nothing.
TEST(CheckpointMutation, ABatchCheckpointsTimeIsBounded) {
  const std::string seed = bp::seed();
  const auto withTime = [&](double t) {
    std::string bytes = seed;
    std::memcpy(&bytes[8 + 4], &t, sizeof t);  // after the magic and the version
    bp::resign(bytes);
    return bytes;
  };
  try {
    BatchCheckpoint::fromBytes(withTime(1e151), "far.bckpt");
    ADD_FAILURE() << "a time of 1e151 was read";
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("1e150"), std::string::npos) << e.what();
  }
  const BatchCheckpoint late = BatchCheckpoint::fromBytes(withTime(1e20), "late.bckpt");
  BatchSimulator batch(bp::scenes(), cp::options());
  batch.step();
  const Eigen::MatrixX3d before = batch.positions(0);
  const double time = batch.time(0);
  try {
    batch.restore(late);
    ADD_FAILURE() << "a time of 1e20 was restored";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("restore: "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("too large for a step"), std::string::npos) << e.what();
  }
  EXPECT_EQ(batch.positions(0), before);
  EXPECT_EQ(batch.time(0), time);
}

}  // namespace
}  // namespace stabint
