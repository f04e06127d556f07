// Changes of L and of its factors (docs/method.md, "Per-frame input", "Contact"): element terms
// and diagonal weights as rank updates of every factor, and the new assembly and factorization
// that replaces them when a change is too large or too big to update.
#include "solver/global_system.hpp"

#include "common/worker_pool.hpp"
#include "scene/scene_data.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <iterator>
#include <utility>
#include <vector>

namespace stabint {
void GlobalSystem::addToDiagonal(int j, double delta, bool refactor) {
  const double one = 1.0;
  addElementTerm(&j, 1, &one, 1, delta, refactor ? FactorChange::Drop : FactorChange::RankUpdate);
}

bool GlobalSystem::changeIsHuge(const int* vertices, int K, const double* a, int R, double delta) const {
  const double c = factors_.empty() ? 0.0 : factors_.begin()->first;  // the smallest c factored
  for (int i = 0; i < K; ++i) {
    double sum = 0.0;
    for (int r = 0; r < R; ++r) sum += a[K * r + i] * a[K * r + i];
    const double change = std::abs(delta) * sum;
    const double diagonal = c * masses_[vertices[i]] + laplacian_.coeff(vertices[i], vertices[i]);
    // The smaller of the entry before and after the change (the change may be a removal).
    const double smaller = std::min(diagonal, diagonal + (delta > 0.0 ? change : -change));
    if (!(change <= kLargestRankUpdate * std::max(smaller, 0.0))) return true;
  }
  return false;
}

void GlobalSystem::refactorAll() {
  // Within a Transaction the factors are computed again into copies (keeping their analysis as
  // below); the originals stay aside, bit for bit, until it commits.
  keepFactors(true);
  std::map<double, std::unique_ptr<Factor>> previous;
  previous.swap(factors_);
  // The factors of the integrator's c at once, one per thread (the blend's two halve a contact
  // set's refactorization), then checked and kept in the order of c.
  std::vector<std::pair<double, std::unique_ptr<Factor>>> computed;
  for (auto& [c, f] : previous) computed.emplace_back(c, std::move(f));
  std::vector<std::exception_ptr> failed(computed.size());
  parallelFor(static_cast<int>(computed.size()), [&](int i) {
    auto& [c, f] = computed[std::size_t(i)];
    try {
      f = computeFactor(c, std::move(f));
    } catch (...) {
      failed[std::size_t(i)] = std::current_exception();
    }
  });
  for (std::size_t i = 0; i < computed.size(); ++i) {
    if (failed[i]) std::rethrow_exception(failed[i]);
    installFactor(computed[i].first, "c", std::move(computed[i].second));
  }
}

template <class FactorUpdate>
void GlobalSystem::updateEveryFactor(const FactorUpdate& update) {
  std::vector<Factor*> factors;
  for (auto& entry : factors_) factors.push_back(entry.second.get());
  std::vector<char> updated(factors.size(), 0);
  parallelFor(static_cast<int>(factors.size()), [&](int i) {
    Factor& f = *factors[std::size_t(i)];
    updated[std::size_t(i)] = update(f) ? 1 : 0;
    f.shapeChanged();
  });
  std::size_t i = 0;
  for (auto it = factors_.begin(); it != factors_.end(); ++i) it = updated[i] ? std::next(it) : factors_.erase(it);
}

const std::vector<int>& GlobalSystem::Factor::rowOf() {
  if (row_of.empty()) {
    const cholmod_factor* f = factor();
    const int n = static_cast<int>(f->n);
    const int* perm = static_cast<const int*>(f->Perm);
    row_of.resize(static_cast<std::size_t>(n));
    for (int r = 0; r < n; ++r) row_of[static_cast<std::size_t>(perm ? perm[r] : r)] = r;
  }
  return row_of;
}

void GlobalSystem::addElementTerm(const int* vertices, int K, const double* a, int R, double delta, FactorChange how) {
  keepLaplacian();
  keepFactors(how == FactorChange::RankUpdate);
  for (int i = 0; i < K; ++i) {
    for (int j = 0; j < K; ++j) {
      double sum = 0.0;
      for (int r = 0; r < R; ++r) sum += a[K * r + i] * a[K * r + j];
      if (sum != 0.0) laplacian_.coeffRef(vertices[i], vertices[j]) += delta * sum;
    }
  }
  laplacianChanged();
  if (how == FactorChange::Drop) {
    factors_.clear();
    return;
  }
  const int n = static_cast<int>(laplacian_.rows());
  const double scale = std::sqrt(std::abs(delta));
  // A failed update (out of memory, or a downdate that lost positive definiteness to round-off)
  // leaves the factor unusable: it is factored again on its next use.
  updateEveryFactor([&](Factor& f) {
    cholmod_factor* factor = f.factor();
    cholmod_common& common = f.cholmod();
    // C = sqrt(|delta|) A^T in the factor's fill-reducing order: vertex v is row k with
    // Perm[k] = v. Each column lists its rows in ascending order, as CHOLMOD requires.
    std::vector<std::pair<int, int>> rows(static_cast<std::size_t>(K));  // (permuted row, k)
    const std::vector<int>& row_of = f.rowOf();
    for (int k = 0; k < K; ++k) rows[static_cast<std::size_t>(k)] = {row_of[static_cast<std::size_t>(vertices[k])], k};
    std::sort(rows.begin(), rows.end());
    cholmod_sparse* c = cholmod_allocate_sparse(n, R, static_cast<std::size_t>(K * R), /*sorted=*/1, /*packed=*/1,
                                                /*stype=*/0, CHOLMOD_REAL, &common);
    if (c == nullptr) return false;
    int* cp = static_cast<int*>(c->p);
    int* ci = static_cast<int*>(c->i);
    double* cx = static_cast<double*>(c->x);
    for (int r = 0; r < R; ++r) {
      cp[r] = K * r;
      for (int k = 0; k < K; ++k) {
        ci[K * r + k] = rows[static_cast<std::size_t>(k)].first;
        cx[K * r + k] = scale * a[K * r + rows[static_cast<std::size_t>(k)].second];
      }
    }
    cp[R] = K * R;
    const bool updated = cholmod_updown(delta > 0.0 ? 1 : 0, c, factor, &common) != 0 && common.status == CHOLMOD_OK;
    cholmod_free_sparse(&c, &common);
    return updated;
  });
}

void GlobalSystem::addToDiagonal(const std::vector<int>& vertices, const std::vector<double>& deltas) {
  keepLaplacian();
  keepFactors(true);
  for (std::size_t i = 0; i < vertices.size(); ++i) laplacian_.coeffRef(vertices[i], vertices[i]) += deltas[i];
  laplacianChanged();
  const int n = static_cast<int>(laplacian_.rows());
  // As addElementTerm: a failed update leaves the factor to be factored again on its next use.
  updateEveryFactor([&](Factor& f) {
    cholmod_factor* factor = f.factor();
    cholmod_common& common = f.cholmod();
    const std::vector<int>& row_of = f.rowOf();
    bool updated = true;
    for (const bool update : {true, false}) {
      std::vector<std::size_t> columns;
      for (std::size_t i = 0; i < deltas.size(); ++i)
        if (update ? deltas[i] > 0.0 : deltas[i] < 0.0) columns.push_back(i);
      if (columns.empty() || !updated) continue;
      const int k = static_cast<int>(columns.size());
      cholmod_sparse* c = cholmod_allocate_sparse(n, static_cast<std::size_t>(k), static_cast<std::size_t>(k),
                                                  /*sorted=*/1, /*packed=*/1, /*stype=*/0, CHOLMOD_REAL, &common);
      if (c == nullptr) return false;
      int* cp = static_cast<int*>(c->p);
      int* ci = static_cast<int*>(c->i);
      double* cx = static_cast<double*>(c->x);
      for (int col = 0; col < k; ++col) {
        const std::size_t i = columns[static_cast<std::size_t>(col)];
        cp[col] = col;
        ci[col] = row_of[static_cast<std::size_t>(vertices[i])];
        cx[col] = std::sqrt(std::abs(deltas[i]));
      }
      cp[k] = k;
      updated = cholmod_updown(update ? 1 : 0, c, factor, &common) != 0 && common.status == CHOLMOD_OK;
      cholmod_free_sparse(&c, &common);
    }
    return updated;
  });
}

int GlobalSystem::WeightChange::updatePrice() const {
  int price = static_cast<int>(diagonal_vertices_.size());
  for (const Term& t : elements_) price += kElementRowPrice * t.R;
  return price;
}

bool GlobalSystem::apply(const WeightChange& change, const SceneData& scene, Update how) {
  if (change.empty() && how == Update::Cheapest) return false;
  bool refactor = how == Update::Refactor || change.updatePrice() > kMaxUpdatePrice;
  const double one = 1.0;
  for (std::size_t i = 0; !refactor && i < change.elements_.size(); ++i) {
    const WeightChange::Term& t = change.elements_[i];
    refactor = changeIsHuge(t.vertices, t.K, t.coefficients, t.R, t.delta);
  }
  for (std::size_t i = 0; !refactor && i < change.diagonal_vertices_.size(); ++i)
    refactor = changeIsHuge(&change.diagonal_vertices_[i], 1, &one, 1, change.diagonal_deltas_[i]);
  if (refactor) {
    assemble(scene);
    refactorAll();
    return true;
  }
  for (const WeightChange::Term& t : change.elements_)
    addElementTerm(t.vertices, t.K, t.coefficients, t.R, t.delta, FactorChange::RankUpdate);
  if (!change.diagonal_vertices_.empty()) addToDiagonal(change.diagonal_vertices_, change.diagonal_deltas_);
  return false;
}

}  // namespace stabint
