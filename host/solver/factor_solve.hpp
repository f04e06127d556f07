#pragma once
// The global step's triangular solves over CHOLMOD's simplicial factor, the three right-hand-side
// columns of K_c x = rhs in one pass over the factor (docs/method.md, "Threads on the CPU").
//
// Why not cholmod_solve2: its simplicial solve also handles the three columns in one pass, but in
// scalar code (three loads, products and stores per factor entry, blocks of at most three
// columns) and, for L^T, one dependent chain of subtractions per column; that, not the factor's
// bytes, bounds it (2-5x the time to stream the factor twice, about twice this solve's time;
// docs/benchmarks.md "Global solve against its bound"). Here a row of the right-hand side is
// one vector of `lanes` doubles (x, y, z and a zero lane, or two of them); chained columns of the
// factor (a supernode: each column has the rows of the one before, less its diagonal) go in
// blocks of up to 8, whose rows below the block are read and written once for the block; L^T's
// sums run on several partial sums; 1 / L(j, j) is computed once. Where the CPU has AVX2 and FMA
// the products are fused multiply-adds (a different rounding from the plain build, so the result
// depends on the instruction set).
//
// Every lane gets the same operations in the same order whatever `lanes` is: a solve of the three
// columns as lanes {x, y, z, 0} and one as {x, y} and {z, 0} on two threads give the same result
// bit for bit.
#include <cholmod.h>

#include <cstddef>
#include <vector>

namespace stabint {

/// Whether solveSimplicial can use `factor`: real, double, simplicial, int indices (LL' as
/// factored, or LDL' after cholmod_updown converted it).
bool simplicialSolveApplies(const cholmod_factor& factor);

/// Solves P^T L L^T P x = b (or P^T L D L^T P x = b) for `columns` (1 to 4) columns of the
/// column-major `rhs` (leading dimension `ld`, at least factor.n), from column `first`, into the
/// same columns of the column-major `x` (leading dimension `ld`). `lanes` (2 or 4, >= columns) is
/// the vector width; `work` is scratch (resized as needed, kept between calls).
void solveSimplicial(const cholmod_factor& factor, const double* rhs, double* x, std::size_t ld, int first, int columns,
                     int lanes, std::vector<double>& work);

/// Columns [0, a_end) and [a_end, b_end) of a postordered factor: two disjoint subtrees of its
/// elimination tree (neither column range holds an ancestor of the other's columns), the columns
/// from b_end on their common ancestors and the rest. {0, 0}: no split.
struct SubtreeSplit {
  int a_end = 0;
  int b_end = 0;
};
/// The split that minimises the backward pass's entries on the longer of two threads plus those
/// above both subtrees.
SubtreeSplit findSubtreeSplit(const cholmod_factor& factor);
/// solveSimplicial for the three columns (lanes {x, y, z, 0}) with the backward pass over the two
/// subtrees on two threads (parallelFor) after the columns above them: the same arithmetic for
/// any thread count (not solveSimplicial's: blocks of chained columns end at the split). The
/// forward pass stays on the calling thread (its updates of the rows above the subtrees would
/// have to be summed in a fixed order). GlobalSystem::solve's path on large systems.
void solveSimplicialSubtrees(const cholmod_factor& factor, const SubtreeSplit& split, const double* rhs, double* x,
                             std::size_t ld, std::vector<double>& work);

/// The trees of a postordered factor's elimination forest (a batch's factor: one tree per scene,
/// or more): tree t is the columns [starts[t], starts[t + 1]), entries[t] the factor's entries in
/// the columns before it (the last of each: n and all of them). Empty when the factor is not
/// postordered.
struct EliminationForest {
  std::vector<int> starts;
  std::vector<double> entries;
  int trees() const { return starts.empty() ? 0 : static_cast<int>(starts.size()) - 1; }
  /// The largest tree's share of the entries (1 for one tree).
  double largestTreeShare() const;
};
EliminationForest findForest(const cholmod_factor& factor);
/// solveSimplicial for the three columns (lanes {x, y, z, 0}), the trees on cpuThreads() threads,
/// each thread a run of whole trees of about equal entries (parallelForRuns), both passes and the
/// permutations. Bit for bit solveSimplicial on any thread count: no tree's column reaches
/// another's rows, and no chain of columns (a block) crosses two trees (a root has no entry below
/// its diagonal), so every tree is solved as the serial solve solves it.
///
/// With `solved` (one flag per tree), only the trees flagged are solved: the rows of the others
/// are left in `x` as they were, and their work is not done (a batch's scenes that take no part in
/// a solve). `threaded` false keeps the trees on the calling thread (small systems, where waking
/// a worker costs more than it saves); the arithmetic is the same either way.
void solveSimplicialForest(const cholmod_factor& factor, const EliminationForest& forest, const double* rhs, double* x,
                           std::size_t ld, std::vector<double>& work, const std::vector<char>* solved = nullptr,
                           bool threaded = true);

}  // namespace stabint
