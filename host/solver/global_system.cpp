#include "solver/global_system.hpp"

#include "scene/scene_data.hpp"
#include "solver/factor_solve.hpp"

#include <stabint/errors.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <new>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace stabint {
namespace {

// The explicit test of a factor that CHOLMOD reports positive definite. CHOLMOD refuses a pivot
// that is <= 0 or NaN as it factors, but an infinite one passes (a c m_i or a diagonal entry of L
// that overflows: its column is then divided by infinity), and the solves would return zeros or
// NaN. Every pivot (the diagonal of L, or D of an LDL' factor) finite and positive, and every
// entry finite. O(entries), against the factorization's O(entries x column length).
bool pivotsFiniteAndPositive(const cholmod_factor& f) {
  const int* p = static_cast<const int*>(f.p);
  const int* nz = static_cast<const int*>(f.nz);
  const double* x = static_cast<const double*>(f.x);
  for (std::size_t j = 0; j < f.n; ++j) {
    const double* column = x + p[j];
    if (!(column[0] > 0.0 && std::isfinite(column[0]))) return false;
    for (int k = 1; k < nz[j]; ++k)
      if (!std::isfinite(column[k])) return false;
  }
  return true;
}

}  // namespace

GlobalSystem::GlobalSystem(const SceneData& scene) : masses_(scene.masses()) { assemble(scene); }

void GlobalSystem::assemble(const SceneData& scene) {
  keepLaplacian();
  const int n = scene.numParticles();
  std::vector<Eigen::Triplet<double>> entries;
  std::size_t count = 0;
  for (const ElementBlock& block : scene.blocks()) {
    const int k = block.type->shape().vertices;
    count += std::size_t(block.count) * std::size_t(k * k);
  }
  entries.reserve(count);
  for (const ElementBlock& block : scene.blocks()) {
    // Block w A^T A over the element's vertex tuple: entry (i, j) = w sum_r A(r, i) A(r, j).
    const ElementShape shape = block.type->shape();
    const int K = shape.vertices, R = shape.rows;
    const int stride = shape.shared_coefficients ? 0 : R * K;
    for (int e = 0; e < block.count; ++e) {
      const int* v = &block.vertices[std::size_t(K) * e];
      const double* a = block.coefficients.data() + std::size_t(stride) * e;
      const double w = block.params[std::size_t(shape.params) * e];
      for (int i = 0; i < K; ++i) {
        for (int j = 0; j < K; ++j) {
          double sum = 0.0;
          for (int r = 0; r < R; ++r) sum += a[K * r + i] * a[K * r + j];
          entries.emplace_back(v[i], v[j], w * sum);
        }
      }
    }
  }
  laplacian_.resize(n, n);
  laplacian_.setFromTriplets(entries.begin(), entries.end());
  laplacianChanged();
}

void GlobalSystem::multiply(double c, const Eigen::MatrixX3d& x, Eigen::MatrixX3d& out,
                            const std::vector<char>* rows_of) const {
  const Eigen::Index n = x.rows();
  out.resize(n, 3);
  if (rows_of && !blocks_.empty()) {
    for (std::size_t b = 0; b < blocks_.size(); ++b)
      if ((*rows_of)[b]) multiplyRows(c, x, out, blocks_[b].first_particle, blocks_[b].num_particles);
    return;
  }
  multiplyRows(c, x, out, 0, n);
}

void GlobalSystem::multiplyRows(double c, const Eigen::MatrixX3d& x, Eigen::MatrixX3d& out, Eigen::Index first,
                                Eigen::Index count) const {
  const auto* begin = laplacian_.outerIndexPtr();
  const auto* rows = laplacian_.innerIndexPtr();
  const double* values = laplacian_.valuePtr();
  const auto* nonzeros = laplacian_.innerNonZeroPtr();  // null when compressed
  for (Eigen::Index i = first; i < first + count; ++i) {
    const double cm = c * masses_[i];
    double a = cm * x(i, 0), b = cm * x(i, 1), d = cm * x(i, 2);
    const auto end = nonzeros ? begin[i] + nonzeros[i] : begin[i + 1];
    for (auto k = begin[i]; k < end; ++k) {
      const Eigen::Index j = rows[k];
      a += values[k] * x(j, 0);
      b += values[k] * x(j, 1);
      d += values[k] * x(j, 2);
    }
    out(i, 0) = a;
    out(i, 1) = b;
    out(i, 2) = d;
  }
}

Eigen::SparseMatrix<double> GlobalSystem::shiftedLaplacian(double c) const {
  // A particle touched by no element has no diagonal entry in L, so add c M as a matrix.
  Eigen::SparseMatrix<double> mass(laplacian_.rows(), laplacian_.cols());
  mass.reserve(Eigen::VectorXi::Ones(laplacian_.cols()));
  for (Eigen::Index j = 0; j < masses_.size(); ++j) mass.insert(j, j) = c * masses_[j];
  return laplacian_ + mass;
}

void GlobalSystem::factor(double c, const char* c_name) { factor(c, c_name, nullptr); }

bool GlobalSystem::Factor::analysedFor(const Eigen::SparseMatrix<double>& k) const {
  const std::size_t columns = static_cast<std::size_t>(k.outerSize()) + 1;
  return k.isCompressed() && pattern_starts.size() == columns && pattern_rows.size() == std::size_t(k.nonZeros()) &&
         std::equal(pattern_starts.begin(), pattern_starts.end(), k.outerIndexPtr()) &&
         std::equal(pattern_rows.begin(), pattern_rows.end(), k.innerIndexPtr());
}

void GlobalSystem::factor(double c, const char* c_name, std::unique_ptr<Factor> reused) {
  if (factors_.count(c)) return;
  installFactor(c, c_name, computeFactor(c, std::move(reused)));
}

std::unique_ptr<GlobalSystem::Factor> GlobalSystem::computeFactor(double c, std::unique_ptr<Factor> reused) const {
  Eigen::SparseMatrix<double> k = shiftedLaplacian(c);
  k.makeCompressed();
  if (reused && reused->analysedFor(k)) {
    // The same fill-reducing order and tree (AMD on the same pattern would find them again):
    // numbers only, about three quarters of a factorization's time on the 50 x 50 cloth.
    reused->shapeChanged();
    reused->factorize(k);
    return reused;
  }
  auto factor = std::make_unique<Factor>();
  // CHOLMOD reports a failure by printing on stdout (into an application's CSV output); the
  // failure is reported by installFactor's exception instead.
  factor->cholmod().print = 0;
  factor->compute(k);
  factor->pattern_starts.assign(k.outerIndexPtr(), k.outerIndexPtr() + k.outerSize() + 1);
  factor->pattern_rows.assign(k.innerIndexPtr(), k.innerIndexPtr() + k.nonZeros());
  return factor;
}

void GlobalSystem::installFactor(double c, const char* c_name, std::unique_ptr<Factor> factor) {
  const bool flagged = factor->info() != Eigen::Success;
  if (!flagged && !simplicialSolveApplies(*factor->factor()))
    throw Error("GlobalSystem::factor: CHOLMOD factor of an unexpected kind");
  if (flagged || !pivotsFiniteAndPositive(*factor->factor())) {
    const double stiffest = laplacian_.nonZeros() > 0 ? laplacian_.diagonal().maxCoeff() : 0.0;
    std::ostringstream what;
    what << "the implicit system c M + L (c = ";
    if (std::string(c_name) != "c") what << c_name << " = ";  // not "c = c = 900"
    what << c << ") is not numerically positive definite: ";
    if (flagged) {
      const double lightest = masses_.size() > 0 ? masses_.minCoeff() : 0.0;
      what << "c times the smallest mass, " << c * lightest
           << ", is lost against the largest element stiffness (diagonal of L), " << stiffest
           << ", in double precision; raise the masses, shorten time_step or lower the stiffnesses";
    } else {
      const double heaviest = masses_.size() > 0 ? masses_.maxCoeff() : 0.0;
      what << "its Cholesky factor has a pivot or an entry that is not finite: c times the largest mass, "
           << c * heaviest << ", or the largest element stiffness (diagonal of L), " << stiffest
           << ", is beyond double precision; lower the masses, lengthen time_step or lower the stiffnesses";
    }
    throw InvalidInputError(what.str());
  }
  keepFactors(true);
  factors_.emplace(c, std::move(factor));
  ++factorizations_;
}

void GlobalSystem::solve(double c, const Eigen::MatrixX3d& rhs, Eigen::MatrixX3d& x, const std::vector<char>* solved) {
  factor(c);
  Factor& f = *factors_.find(c)->second;
  cholmod_factor* l = f.factor();
  const Eigen::Index n = rhs.rows();
  x.resize(n, 3);
  // One pass over the factor for the three columns (the columns split over threads would each
  // read the whole factor; docs/benchmarks.md, "Global solve against its bound"). A batch's
  // factor, a forest of many trees none of which holds half the entries, is solved tree by tree on
  // every thread (the serial arithmetic); on other large systems the backward pass goes over two
  // subtrees on two threads. Both by the size alone, so that the arithmetic is the same on any
  // thread count.
  // The factors made here are simplicial, double, int-indexed (Eigen's CholmodSimplicialLLT), and
  // cholmod_updown keeps them so.
  if (!simplicialSolveApplies(*l)) throw Error("GlobalSystem::solve: CHOLMOD factor of an unexpected kind");
  if (n >= kForestRows && !f.shape_known) {
    // A forest whose largest tree holds half of the entries or more gains less than the split.
    f.forest = findForest(*l);
    if (f.forest.largestTreeShare() > 0.5) f.forest = {};
    f.split = n >= kSubtreeRows ? findSubtreeSplit(*l) : SubtreeSplit{};
    f.shape_known = true;
  }
  // Some blocks alone: tree by tree, the arithmetic of the serial and the forest's solves (not
  // the subtree split's, which the whole solve takes on a large system with a dominant tree).
  const bool forest = n >= kForestRows && f.forest.trees() > 1;
  const bool split = !forest && n >= kSubtreeRows && f.split.b_end > 0;
  if (solved && blocks_.size() > 1 && !split && std::find(solved->begin(), solved->end(), 0) != solved->end() &&
      solveBlocks(f, rhs, x, *solved))
    return;
  if (forest) {
    solveSimplicialForest(*l, f.forest, rhs.data(), x.data(), static_cast<std::size_t>(n), solve_work_);
  } else if (split) {
    solveSimplicialSubtrees(*l, f.split, rhs.data(), x.data(), static_cast<std::size_t>(n), solve_work_);
  } else {
    solveSimplicial(*l, rhs.data(), x.data(), static_cast<std::size_t>(n), 0, 3, 4, solve_work_);
  }
}

bool GlobalSystem::solveBlocks(Factor& f, const Eigen::MatrixX3d& rhs, Eigen::MatrixX3d& x,
                               const std::vector<char>& solved) {
  const cholmod_factor& l = *f.factor();
  if (!f.trees_known) {
    f.trees = findForest(l);
    f.tree_block.clear();
    const int* perm = static_cast<const int*>(l.Perm);
    for (int tree = 0; tree < f.trees.trees(); ++tree) {
      // Any row of the tree tells its block: no element couples two blocks, so no tree holds rows
      // of two.
      const int column = f.trees.starts[std::size_t(tree)];
      const int row = perm ? perm[column] : column;
      const auto after = std::upper_bound(blocks_.begin(), blocks_.end(), row,
                                          [](int r, const SceneSegment& b) { return r < b.first_particle; });
      f.tree_block.push_back(static_cast<int>(after - blocks_.begin()) - 1);
    }
    f.trees_known = true;
  }
  if (f.trees.trees() == 0) return false;
  solved_trees_.resize(f.tree_block.size());
  for (std::size_t tree = 0; tree < f.tree_block.size(); ++tree)
    solved_trees_[tree] = solved[std::size_t(f.tree_block[tree])];
  // Threads where the whole solve would take them (kForestRows), the same arithmetic either way.
  solveSimplicialForest(l, f.trees, rhs.data(), x.data(), static_cast<std::size_t>(rhs.rows()), solve_work_,
                        &solved_trees_, rhs.rows() >= kForestRows);
  return true;
}

int GlobalSystem::solveConjugateGradient(double c, const Eigen::MatrixX3d& rhs, Eigen::MatrixX3d& x, int iterations,
                                         double tolerance, const std::vector<char>* solved) {
  auto found = cg_systems_.find(c);
  if (found == cg_systems_.end()) {
    std::vector<std::unique_ptr<CgSystem>> systems;
    const Eigen::SparseMatrix<double> shifted = shiftedLaplacian(c);
    for (std::size_t b = 0; b < std::max<std::size_t>(1, blocks_.size()); ++b) {
      auto system = std::make_unique<CgSystem>();
      if (blocks_.empty())
        system->matrix = shifted;
      else
        system->matrix = shifted.block(blocks_[b].first_particle, blocks_[b].first_particle, blocks_[b].num_particles,
                                       blocks_[b].num_particles);
      system->cg.compute(system->matrix);
      systems.push_back(std::move(system));
    }
    found = cg_systems_.emplace(c, std::move(systems)).first;
  }
  int most = 0;
  for (std::size_t b = 0; b < found->second.size(); ++b) {
    if (solved && !blocks_.empty() && !(*solved)[b]) continue;
    auto& cg = found->second[b]->cg;
    cg.setMaxIterations(iterations);
    cg.setTolerance(tolerance);  // 0: Eigen's threshold becomes the smallest normal number (a fixed count)
    for (int k = 0; k < 3; ++k) {
      if (blocks_.empty()) {
        Eigen::VectorXd column = cg.solveWithGuess(rhs.col(k), x.col(k));
        x.col(k) = column;
      } else {
        // The block's rows copied out, so that CG runs on the vectors its scene alone has.
        const Eigen::VectorXd block_rhs = rhs.col(k).segment(blocks_[b].first_particle, blocks_[b].num_particles);
        const Eigen::VectorXd block_x = x.col(k).segment(blocks_[b].first_particle, blocks_[b].num_particles);
        Eigen::VectorXd column = cg.solveWithGuess(block_rhs, block_x);
        x.col(k).segment(blocks_[b].first_particle, blocks_[b].num_particles) = column;
      }
      most = std::max(most, static_cast<int>(cg.iterations()));
    }
  }
  return most;
}

void GlobalSystem::setBlocks(const std::vector<SceneSegment>& blocks) {
  blocks_ = blocks.size() > 1 ? blocks : std::vector<SceneSegment>{};
  cg_systems_.clear();
  for (auto& entry : factors_) entry.second->trees_known = false;  // their trees' blocks
}

std::unique_ptr<GlobalSystem::Factor> GlobalSystem::Factor::copy() {
  auto f = std::make_unique<Factor>();
  f->cholmod().print = 0;
  f->m_cholmodFactor = cholmod_copy_factor(m_cholmodFactor, &f->cholmod());
  if (f->m_cholmodFactor == nullptr) throw std::bad_alloc();
  f->m_isInitialized = m_isInitialized;
  f->m_info = m_info;
  f->m_analysisIsOk = m_analysisIsOk;
  f->m_factorizationIsOk = m_factorizationIsOk;
  f->m_shiftOffset[0] = m_shiftOffset[0];
  f->m_shiftOffset[1] = m_shiftOffset[1];
  f->forest = forest;
  f->split = split;
  f->shape_known = shape_known;
  f->trees = trees;
  f->tree_block = tree_block;
  f->trees_known = trees_known;
  f->row_of = row_of;
  f->pattern_starts = pattern_starts;
  f->pattern_rows = pattern_rows;
  return f;
}

void GlobalSystem::keepLaplacian() {
  if (!kept_.open || kept_.has_laplacian) return;
  kept_.laplacian = laplacian_;
  kept_.has_laplacian = true;
}

void GlobalSystem::keepFactors(bool copy_back) {
  if (!kept_.open || kept_.has_factors) return;
  std::map<double, std::unique_ptr<Factor>> copies;
  if (copy_back)
    for (auto& [c, factor] : factors_) copies.emplace(c, factor->copy());
  kept_.factors = std::move(factors_);
  factors_ = std::move(copies);
  kept_.has_factors = true;
}

void GlobalSystem::rollback() noexcept {
  if (kept_.has_laplacian) {
    laplacian_.swap(kept_.laplacian);
    // A new version, not the old one: a copy of L made meanwhile must not pass for current.
    laplacianChanged();
  }
  if (kept_.has_factors) factors_ = std::move(kept_.factors);
  dropKept();
}

void GlobalSystem::dropKept() noexcept {
  kept_.factors.clear();
  try {
    kept_.laplacian.resize(0, 0);  // frees its entries (keeps one index)
  } catch (const std::bad_alloc&) {
    // The copy stays until the next transaction replaces it.
  }
  kept_.open = kept_.has_laplacian = kept_.has_factors = false;
}

GlobalSystem::Transaction::Transaction(GlobalSystem& system) : system_(system) {
  if (system_.kept_.open) throw Error("GlobalSystem::Transaction: one is open already");
  system_.kept_.open = true;
}

GlobalSystem::Transaction::~Transaction() {
  if (!committed_) system_.rollback();
}

void GlobalSystem::Transaction::commit() {
  system_.dropKept();
  committed_ = true;
}

}  // namespace stabint
