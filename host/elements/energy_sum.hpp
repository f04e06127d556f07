#pragma once
// How the CPU reference sums the energies of a range of elements (a block, or one scene's part of
// it in a batch): in chunks of kEnergyChunk consecutive elements counted from the range's first,
// each chunk added in element order from 0, the chunks' sums then added in order from 0. One rule
// for every pass and path, so that a pass gives the same bits on one thread, split over threads
// (the stored energies, sumEnergies) and per scene of a batch (whose range starts at the scene's
// first element, as its own Simulator's starts at 0).
//
// Why chunks rather than one chain in element order: a pass split over threads stores its
// elements' energies and the calling thread sums them afterwards. One chain of dependent
// additions waits on each addition's latency; independent chunk sums run at the additions'
// throughput (the measurements: docs/benchmarks.md, "Threads in the element passes").

namespace stabint {

/// Elements per chunk of an energy sum.
inline constexpr int kEnergyChunk = 64;

/// The sum of a range's energies formed as a pass computes them, element by element: add(i, e)
/// for the range's element i (0, 1, ... in order; an element left out adds nothing, as adding its
/// zero energy would not change the sum).
class EnergySum {
 public:
  void add(int i, double energy) {
    if (i >= chunk_end_) {
      total_ += chunk_;
      chunk_ = 0.0;
      chunk_end_ = (i / kEnergyChunk + 1) * kEnergyChunk;
    }
    chunk_ += energy;
  }
  /// add(i + l, energies[l]) for l in [0, count).
  void add(int i, const double* energies, int count) {
    for (int l = 0; l < count; ++l) add(i + l, energies[l]);
  }
  double total() const { return total_ + chunk_; }

 private:
  double total_ = 0.0, chunk_ = 0.0;
  int chunk_end_ = kEnergyChunk;
};

/// The same sum of `count` stored energies (energies[i] of the range's element i), bit for bit,
/// with kGroups chunks summed side by side.
inline double sumEnergies(const double* energies, int count) {
  constexpr int kGroups = 8;
  double total = 0.0;
  int first = 0;
  for (; first + kGroups * kEnergyChunk <= count; first += kGroups * kEnergyChunk) {
    double chunk[kGroups] = {};
    for (int i = 0; i < kEnergyChunk; ++i)
      for (int g = 0; g < kGroups; ++g) chunk[g] += energies[first + g * kEnergyChunk + i];
    for (int g = 0; g < kGroups; ++g) total += chunk[g];
  }
  for (; first < count; first += kEnergyChunk) {
    double chunk = 0.0;
    for (int i = first; i < count && i < first + kEnergyChunk; ++i) chunk += energies[i];
    total += chunk;
  }
  return total;
}

}  // namespace stabint
