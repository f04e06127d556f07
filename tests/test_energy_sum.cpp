// The rule by which the CPU reference sums a range of element energies (host/elements/energy_sum.hpp):
// chunks of kEnergyChunk from the range's first element. The pass that sums as it goes
// (EnergySum) and the calling thread's sum of a threaded pass's stored energies (sumEnergies) must
// agree bit for bit, or a pass would depend on its thread count; the passes themselves are
// checked against each other in test_cpu_threads.cpp and per scene of a batch in
// test_batch_of_one.cpp.
#include "elements/energy_sum.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace stabint {
namespace {

// Energies over fifteen orders of magnitude (a stiff pin's next to a slack spring's), so that the
// order of additions shows in the last bits.
std::vector<double> energies(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> exponent(-12.0, 3.0);
  std::vector<double> e(static_cast<std::size_t>(count));
  for (double& v : e) v = std::pow(10.0, exponent(rng));
  return e;
}

double streamed(const std::vector<double>& e) {
  EnergySum sum;
  for (int i = 0; i < static_cast<int>(e.size()); ++i) sum.add(i, e[static_cast<std::size_t>(i)]);
  return sum.total();
}

TEST(EnergySum, StoredSumIsTheStreamedSumBitForBit) {
  // Every remainder of the chunks and of the side-by-side groups of chunks (8 x 64 = 512).
  std::vector<int> counts;
  for (int n = 0; n <= 1100; ++n) counts.push_back(n);
  for (int n : {4095, 4096, 4097, 14504, 23914}) counts.push_back(n);
  for (int n : counts) {
    const std::vector<double> e = energies(n, static_cast<unsigned>(n) + 1);
    EXPECT_EQ(sumEnergies(e.data(), n), streamed(e)) << n << " energies";
  }
}

TEST(EnergySum, IsTheSumOfChunksInOrder) {
  // The rule as docs state it, written out: each chunk from 0 in element order, then the chunks.
  const int n = 1000;
  const std::vector<double> e = energies(n, 7);
  double total = 0.0;
  for (int first = 0; first < n; first += kEnergyChunk) {
    double chunk = 0.0;
    for (int i = first; i < n && i < first + kEnergyChunk; ++i) chunk += e[static_cast<std::size_t>(i)];
    total += chunk;
  }
  EXPECT_EQ(streamed(e), total);
  // ... which is not the one chain in element order the passes used before (else this test
  // would not tell the rules apart).
  double chain = 0.0;
  for (double v : e) chain += v;
  EXPECT_NE(total, chain);
}

TEST(EnergySum, ElementsLeftOutAddNothing) {
  // Contact's pass skips the pairs of weight 0 (energy 0) that kindPass adds: the same sum,
  // whole chunks left out included.
  const int n = 700;
  std::vector<double> e = energies(n, 11);
  for (int i = 0; i < n; ++i)
    if (i % 3 == 0 || (i >= 128 && i < 256)) e[static_cast<std::size_t>(i)] = 0.0;
  EnergySum skipping;
  for (int i = 0; i < n; ++i)
    if (e[static_cast<std::size_t>(i)] != 0.0) skipping.add(i, e[static_cast<std::size_t>(i)]);
  EXPECT_EQ(skipping.total(), streamed(e));
  EXPECT_EQ(EnergySum().total(), 0.0);
}

TEST(EnergySum, IsAccurate) {
  // Each energy passes through at most kEnergyChunk - 1 additions in its chunk and n / kEnergyChunk
  // in the chunks' sum: for positive terms the relative error is at most (63 + 374) u, u = 2^-53,
  // about 5e-14 (Higham, "Accuracy and Stability of Numerical Algorithms", 4.2).
  const int n = 23914;
  const std::vector<double> e = energies(n, 3);
  long double exact = 0.0L;
  for (double v : e) exact += static_cast<long double>(v);
  const double bound = (kEnergyChunk - 1 + n / kEnergyChunk + 1) * std::ldexp(1.0, -53);
  EXPECT_LE(std::abs(static_cast<double>((static_cast<long double>(sumEnergies(e.data(), n)) - exact) / exact)), bound);
}

}  // namespace
}  // namespace stabint
