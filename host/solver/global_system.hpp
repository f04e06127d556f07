#pragma once
// The global step of the local/global solver: K_c = c M + L with L = sum_e w_e A_e^T A_e, an
// `n by n` scalar matrix shared by x, y and z. Factored once per distinct c with CHOLMOD and
// reused for every iteration of every step (docs/method.md section 2).
#include "scene/scene_batch.hpp"
#include "solver/factor_solve.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>

#include <map>
#include <memory>
#include <vector>

namespace stabint {

class SceneData;

class GlobalSystem {
 public:
  explicit GlobalSystem(const SceneData& scene);

  /// L assembled again from the scene's current element weights (after changes whose factors
  /// the caller refactors with refactorAll). The result depends only on those weights, not on
  /// the changes that led to them.
  void assemble(const SceneData& scene);

  /// Factors K_c unless it already is. A K_c that is not numerically positive definite is an
  /// InvalidInputError naming the masses, the stiffness and `c_name` (how c follows from the
  /// options, e.g. "1/time_step^2"): one that CHOLMOD flags (masses too small for the stiffnesses
  /// at this c, e.g. 1e-300 kg against 8e149 N/m), and, by an explicit test of the factor CHOLMOD
  /// accepted, one whose pivots are not all finite and positive or whose entries are not all
  /// finite (an infinite pivot passes CHOLMOD's test: c m_i beyond double's range, e.g. 1e5 kg at
  /// time_step 1e-152). Nothing is printed (CHOLMOD would print on stdout).
  void factor(double c, const char* c_name = "c");

  /// Solves K_c x = rhs for the three columns of `rhs` (`n by 3`), factoring K_c on first use:
  /// one pass over the factor for all three columns (host/solver/factor_solve.hpp). From
  /// kSubtreeRows particles the backward pass runs over two subtrees of the elimination tree on
  /// up to two threads (cpuThreads()), the same arithmetic on any thread count, so the same
  /// result bit for bit.
  ///
  /// With `solved` (one flag per block of setBlocks), only the blocks flagged are solved: the
  /// rows of the others are left in `x` as they were, where the factor's elimination forest shows
  /// its trees (CHOLMOD's postordered factors do), and their work is not done. The rows solved are
  /// those of the whole solve bit for bit (a batch's scenes that take no part in a solve:
  /// stopped, or not stepping).
  void solve(double c, const Eigen::MatrixX3d& rhs, Eigen::MatrixX3d& x, const std::vector<char>* solved = nullptr);
  /// From this many particles solve() splits the backward pass over two subtrees (below it the
  /// second thread costs more than it saves; docs/benchmarks.md "Global solve against its
  /// bound").
  static constexpr Eigen::Index kSubtreeRows = 15000;
  /// From this many particles solve() runs the trees of a factor that is a forest (a batch's: one
  /// tree per scene) on every thread, where no tree holds half the entries: the serial solve's
  /// arithmetic, tree by tree (docs/method.md, "Threads on the CPU").
  static constexpr Eigen::Index kForestRows = 4000;

  /// Jacobi-preconditioned conjugate gradients on K_c x = rhs (GlobalSolve::ConjugateGradient on
  /// the host: the CPU reference of the OpenCL device's CG, the same algorithm in double, Eigen's
  /// ConjugateGradient with its DiagonalPreconditioner), each column warm-started from `x`:
  /// `iterations` iterations, or fewer once ||rhs - K_c x|| < tolerance ||rhs|| (tolerance > 0).
  /// Returns the largest iteration count of the three columns. With blocks (setBlocks), CG runs
  /// on each diagonal block on its own, as that block's own system would run it.
  /// With `solved` and blocks, only the blocks flagged run (the others' rows of `x` stay).
  int solveConjugateGradient(double c, const Eigen::MatrixX3d& rhs, Eigen::MatrixX3d& x, int iterations,
                             double tolerance, const std::vector<char>* solved = nullptr);

  /// out = (c M + L) x for the three columns at once (L symmetric: its stored columns are its
  /// rows, read once for all three columns). With `rows_of` (one flag per block of setBlocks),
  /// the rows of the blocks flagged alone; the others' rows of `out` are left as they were.
  void multiply(double c, const Eigen::MatrixX3d& x, Eigen::MatrixX3d& out,
                const std::vector<char>* rows_of = nullptr) const;

  /// The rows of K_c's diagonal blocks (a batch's scenes: first row, count), which no element
  /// couples: solveConjugateGradient then runs one CG per block, so that one scene's residuals
  /// and step lengths never depend on another's. Empty or one block: the whole system.
  void setBlocks(const std::vector<SceneSegment>& blocks);

  /// Drops every factor (GlobalSolve::ConjugateGradient factors only to validate the system, so
  /// element changes then update no factor).
  void dropFactors() {
    keepFactors(false);
    factors_.clear();
  }

  /// L = sum_e w_e A_e^T A_e (assembled once).
  const Eigen::SparseMatrix<double>& stiffnessLaplacian() const { return laplacian_; }
  /// Lumped masses (the M of c M + L).
  const Eigen::VectorXd& masses() const { return masses_; }
  /// Incremented by every change of L (assemble, addToDiagonal, addElementTerm): a copy of L
  /// elsewhere (the OpenCL device's) is stale when its version differs.
  int laplacianVersion() const { return laplacian_version_; }
  /// Number of factorizations done so far (one per distinct c).
  int factorizations() const { return factorizations_; }

  /// L(j, j) += delta: a pin of stiffness delta attached to (delta > 0) or detached from
  /// (delta < 0) particle j. Every existing factor is updated with a rank-1 CHOLMOD update or
  /// downdate (cholmod_updown) instead of a refactorization; with `refactor` they are dropped and
  /// factored again on their next use instead (for comparison).
  void addToDiagonal(int j, double delta, bool refactor = false);

  /// Largest change of a diagonal entry of c M + L that addElementTerm carries (about 6 of the
  /// 16 digits of the entry and of the factor's row).
  static constexpr double kLargestRankUpdate = 1e6;
  /// Whether L += delta A^T A (as addElementTerm) changes a diagonal entry of c M + L, at the
  /// smallest c factored so far, by more than kLargestRankUpdate times the smaller of the entry
  /// before and after. [project rule] Such a change (a grab of 1e20 N/m on a 0.25 g particle, and
  /// the release that takes it off again) would cancel most of the entry's digits in L and in the
  /// updated factor: the caller assembles L from the scene and refactors instead.
  bool changeIsHuge(const int* vertices, int K, const double* a, int R, double delta) const;

  /// How addElementTerm treats the existing factors.
  enum class FactorChange {
    RankUpdate,  // a rank-R cholmod_updown of each
    Drop,        // dropped, factored again on their next use (as addToDiagonal's `refactor`)
  };
  /// L += delta A^T A over `vertices` (K of them) with A the R by K row-major `coefficients`: an
  /// element's weight changed by delta (a stiffness change, an element enabled or disabled). By
  /// default the factors get a rank-R update or downdate (C = sqrt|delta| A^T, in their permuted
  /// order). A change that changeIsHuge() would spoil them and L itself: assemble and refactor
  /// instead.
  void addElementTerm(const int* vertices, int K, const double* coefficients, int R, double delta,
                      FactorChange how = FactorChange::RankUpdate);
  /// Factors every c factored so far again from the current L. Where the pattern of K_c is the
  /// one a factor was analysed for (a change of weights, as the contact set makes), the factor
  /// keeps its fill-reducing order and elimination tree and only its numbers are computed again.
  void refactorAll();

  /// L(v_i, v_i) += delta_i for each i, every existing factor updated with one rank-k CHOLMOD
  /// update for the positive deltas followed by one rank-k downdate for the negative ones (in
  /// the order given): the contact set's change at a step's start. Deterministic: the same
  /// calls on the same factors give the same factors, bit for bit.
  void addToDiagonal(const std::vector<int>& vertices, const std::vector<double>& deltas);

  /// Changes of element weights to apply as one (apply): element terms delta A^T A (a stiffness
  /// change, an element enabled or disabled; the pointers are the scene's block data and must
  /// stay valid until apply) and diagonal terms (a pin or a contact pair: a weight at one
  /// particle).
  class WeightChange {
   public:
    void addElement(const int* vertices, int K, const double* coefficients, int R, double delta) {
      elements_.push_back({vertices, K, coefficients, R, delta});
    }
    void addDiagonal(int vertex, double delta) {
      diagonal_vertices_.push_back(vertex);
      diagonal_deltas_.push_back(delta);
    }
    bool empty() const { return elements_.empty() && diagonal_vertices_.empty(); }
    /// The price of updating the factors in place, in diagonal columns: an element's row counts
    /// kElementRowPrice (its update spans up to four vertices' paths of the elimination tree and
    /// is one cholmod_updown call per element; the diagonal terms share one call).
    int updatePrice() const;
    static constexpr int kElementRowPrice = 4;

   private:
    friend class GlobalSystem;
    struct Term {
      const int* vertices;
      int K;
      const double* coefficients;
      int R;
      double delta;
    };
    std::vector<Term> elements_;
    std::vector<int> diagonal_vertices_;
    std::vector<double> diagonal_deltas_;
  };
  /// Whether apply() may update the factors in place or must factor them again.
  enum class Update { Cheapest, Refactor };
  /// [project rule] The one path of every run-time change of L's weights (element changes, the
  /// pin set, the contact set, restores), with one update-or-refactor policy. The scene already
  /// holds the new weights. L is assembled from them and every factor computed again when
  /// - a term changeIsHuge() (its update would cancel the entry's digits),
  /// - the change's updatePrice() is over kMaxUpdatePrice (past that, a new assembly and
  ///   factorization is the cheaper: docs/method.md, "Per-frame input"), or
  /// - `how` is Refactor (the caller's own reason: the contact log's bound);
  /// else L takes the terms and every factor their rank updates: each element term one rank-R
  /// update or downdate in order, then the diagonal terms one rank-k update of the positive ones
  /// and one rank-k downdate of the negative ones. Returns whether it refactored (a refactored
  /// L carries no round-off of earlier updates). InvalidInputError when the new system does not
  /// factor (then L and the factors are the caller's to put back).
  bool apply(const WeightChange& change, const SceneData& scene, Update how = Update::Cheapest);
  static constexpr int kMaxUpdatePrice = 256;

  /// [project rule] A refused change puts L and the factors back as they were, bit for bit: a
  /// factor computed again from the old weights, or updated back, rounds differently from the one
  /// it replaces (whose rank updates are part of it), and every later step would drift from an
  /// untouched twin. While a Transaction is open the first change of L keeps a copy of it and the
  /// first change of the factors keeps the factors (moved aside, with copies left in their place
  /// where they are updated in place); its destructor puts them back unless commit() was called.
  /// Nothing is copied when nothing changes. One at a time.
  class Transaction {
   public:
    explicit Transaction(GlobalSystem& system);
    ~Transaction();
    Transaction(const Transaction&) = delete;
    Transaction& operator=(const Transaction&) = delete;
    /// Keeps the changes: what was kept is dropped.
    void commit();

   private:
    GlobalSystem& system_;
    bool committed_ = false;
  };

 private:
  // Simplicial CHOLMOD: solve() reads its columns directly (factor_solve.hpp), which took 0.1-0.3
  // of the time of CHOLMOD's supernodal solve with Debian's reference BLAS and 0.3-0.6 with
  // OpenBLAS, and cholmod_updown (the rank updates) needs a simplicial factor. The subclass
  // reaches the cholmod_factor that Eigen keeps protected, for the solve and the rank updates.
  struct Factor : Eigen::CholmodSimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
    cholmod_factor* factor() { return m_cholmodFactor; }
    // The elimination forest's trees (solve() from kForestRows rows; none where one tree holds
    // half of the entries) and where solve() splits the backward pass over two subtrees (from
    // kSubtreeRows rows), found on first use and again after a rank update (which may change the
    // tree).
    EliminationForest forest;
    SubtreeSplit split;
    bool shape_known = false;
    // For solves of some blocks: every tree of the forest (whatever its share) and the block
    // (setBlocks) each belongs to, found on first use and again after a rank update.
    EliminationForest trees;
    std::vector<int> tree_block;
    bool trees_known = false;
    // A rank update may have changed the elimination tree.
    void shapeChanged() { shape_known = trees_known = false; }
    // Row of vertex v in the fill-reducing order (Perm[row] = v), made on the first rank update:
    // the permutation is the factorization's, which the updates keep, so one change costs its
    // element's rows instead of a search over every row (a batch's element change).
    std::vector<int> row_of;
    const std::vector<int>& rowOf();
    // The pattern of the K_c it was analysed for (column starts, row indices): refactorAll keeps
    // the analysis while a new K_c has the same.
    std::vector<int> pattern_starts, pattern_rows;
    bool analysedFor(const Eigen::SparseMatrix<double>& k) const;
    // An independent copy: CHOLMOD's factor (cholmod_copy_factor, into the copy's own workspace)
    // and every member above (what was found about it, the pattern it was analysed for).
    // std::bad_alloc when memory runs out.
    std::unique_ptr<Factor> copy();
  };
  // factor(c, c_name), computing the numbers into `reused` where it was analysed for K_c's pattern.
  void factor(double c, const char* c_name, std::unique_ptr<Factor> reused);
  // The factor of K_c (into `reused` where it was analysed for K_c's pattern), unchecked. Reads L
  // and the masses only, so that several c are factored at once on their own threads.
  std::unique_ptr<Factor> computeFactor(double c, std::unique_ptr<Factor> reused) const;
  // Checks a computed factor (InvalidInputError naming c_name when K_c is not numerically positive
  // definite) and keeps it as the factor of c.
  void installFactor(double c, const char* c_name, std::unique_ptr<Factor> factor);
  // update(f) for every factor, each on its own thread (one factor's rank update is serial
  // arithmetic, so the results do not depend on the thread count); a factor whose update returns
  // false is dropped, to be factored again on its next use.
  template <class FactorUpdate>
  void updateEveryFactor(const FactorUpdate& update);
  // What an open Transaction keeps: L and the factors as they were before their first change.
  struct Kept {
    bool open = false;
    bool has_laplacian = false;
    bool has_factors = false;
    Eigen::SparseMatrix<double> laplacian;
    std::map<double, std::unique_ptr<Factor>> factors;
  };
  Kept kept_;
  // Called by every change of L or of the factors before it changes them: within a Transaction,
  // the first keeps L (a copy), respectively the factors (moved aside; `copy_back`: copies stay
  // in factors_, for a change that updates them in place).
  void keepLaplacian();
  void keepFactors(bool copy_back);
  // Puts what the Transaction kept back (noexcept: only moves and swaps) and closes it.
  void rollback() noexcept;
  // Frees what the Transaction kept and closes it.
  void dropKept() noexcept;
  int factorizations_ = 0;
  int laplacian_version_ = 0;
  // K_c = c M + L (or one diagonal block of it) and its CG solver (which keeps a reference to it),
  // per c and block, dropped when L changes.
  struct CgSystem {
    Eigen::SparseMatrix<double> matrix;
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg;
  };
  std::map<double, std::vector<std::unique_ptr<CgSystem>>> cg_systems_;
  std::vector<SceneSegment> blocks_;  // setBlocks; empty: the whole system
  // Every change of L goes through here: the copies made from it (CG systems here, the device's
  // CSR through laplacianVersion) follow.
  void laplacianChanged() {
    ++laplacian_version_;
    cg_systems_.clear();
  }
  Eigen::SparseMatrix<double> shiftedLaplacian(double c) const;  // c M + L
  // multiply()'s rows [first, first + count).
  void multiplyRows(double c, const Eigen::MatrixX3d& x, Eigen::MatrixX3d& out, Eigen::Index first,
                    Eigen::Index count) const;

  Eigen::SparseMatrix<double> laplacian_;
  Eigen::VectorXd masses_;
  std::map<double, std::unique_ptr<Factor>> factors_;
  // The solve's work buffer (the permuted right-hand side, a row of four doubles per particle),
  // kept from one solve to the next.
  std::vector<double> solve_work_;
  std::vector<char> solved_trees_;  // solve()'s trees to solve, from its blocks (kept: no allocation)
  // solve() of the blocks flagged in `solved` alone; false where the factor shows no forest.
  bool solveBlocks(Factor& f, const Eigen::MatrixX3d& rhs, Eigen::MatrixX3d& x, const std::vector<char>& solved);
};

}  // namespace stabint
