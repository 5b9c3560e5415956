#pragma once
// The element matrices of fairness_matrix (fairness.cpp), one per class of
// faces, from the derivative rows at their pieces' points, and K assembled
// from them row by row on the core's threads. Internal to the fit layer.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "fairness_elements.hpp"
#include "fairness_exact.hpp"
#include "fairness_pieces.hpp"
#include "fairness_terms.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/surface.hpp"

namespace sorpia::fairness_detail {

// One thread's work space.
struct Worker {
  std::vector<std::int32_t> local;  // column -> its place in `cols`, -1 elsewhere
  std::vector<std::int32_t> cols;
  std::vector<double> a, e, qd;
  std::vector<std::int32_t> first;  // per control point of a shared class: its place in `cols`, or -1
};

// What an element needs besides the rows: the weights, the Gauss terms and
// the closed forms.
struct ElementRules {
  const std::vector<Term>& terms;
  const ExactForms& exact;
  double thin_plate, membrane;
};

// A face's element matrix from the rows of its pieces' points: w.e (upper
// triangle, row-major) over the sorted global columns w.cols, w.local their
// places (store_element clears them).
void element_matrix(const SurfaceRows& rows, const double* weights, const Piece* pieces, std::size_t n_pieces,
                 const ElementRules& er, const std::vector<Term>& terms, Worker& w);

// The element matrix of element_matrix (w.e, upper triangle over w.cols) as
// the full symmetric matrix of class c over its columns: for a shared class
// the control points `cv` of its representative (distinct, in its class's order),
// else the face's own columns w.cols. Clears w.local.
void store_element(Worker& w, const std::int32_t* cv, std::size_t n_cv, std::size_t c, Elements& el);

// K in CSR from the element matrices, assembled row by row (threads take
// ranges of rows): row r's columns are the union of the columns of the faces
// that have r among theirs, sorted (or, without sorted_columns, in the order
// they first appear); its values the sum of those faces' rows for r
// (add_element_row, from the slots found with the columns). No list of
// entries, no sort of all entries: each row's few columns are sorted on
// their own.
CsrMatrix assemble(const Elements& el, std::size_t n_rows, int n_threads, bool sorted_columns);

}  // namespace sorpia::fairness_detail
