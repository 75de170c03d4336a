#pragma once
// The total cost of docs/design.md §1 and its analytic gradient:
//   Newton:  1/2 sum_p |r_p / F0|^2,  r_p = m(a - g) - F_contact + sum_e f_e c_e dk_e/dx_p
//   bands:   1/2 sum_e (excess_e * lambda_e / F0)^2   (stretch, bend, shear)
//   memory:  1/2 mu sum_e ((f_e - stop_e) * lambda_e / F0)^2, stop_e the
//            hysteresis target clamp(f_e at step start, band at q_e); counted
//            with its element's term (stretch, bend or shear)
// Unknowns: positions of free particles and the force of every active element.
//
// Evaluation runs in passes over the active lists; elements write their
// contributions into buffers kept in list order and each particle gathers its
// own in a fixed order, so no two threads write one value (no atomics) and
// results are the same for any thread count or schedule.
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "mesh/active_lists.hpp"
#include "mesh/cloth.hpp"
#include "mesh/topology.hpp"
#include "solver/band_active_set.hpp"
#include "solver/elements/edge_K.hpp"
#include "solver/elements/kept_K.hpp"
#include "solver/elements/v3.hpp"
#include "solver/halo.hpp"
#include "solver/list_walk.hpp"
#include "solver/local_numbering.hpp"
#include "solver/loops.hpp"
#include "solver/memory_table.hpp"
#include "solver/model.hpp"
#include "solver/multigrid/block_matrix.hpp"
#include "solver/reducer.hpp"
#include "solver/self_contact.hpp"

namespace drape {

struct EdgeFour;    // elements/edge_K.hpp
struct TripleFour;  // elements/triple_K.hpp

struct BlockMatrix;

struct CostTerms {
  double newton = 0, stretch = 0, bend = 0, shear = 0;
  double total() const { return newton + stretch + bend + shear; }
};

class Evaluator {
 public:
  Evaluator(const Cloth& cloth, const Model& model, const ActiveLists& lists, const Tiling& tiling,
            const LoopPolicy& policy, const Reducer& reducer, const Halo& halo = no_halo());

  // The entry points that take z first refresh its ghost entries (Halo;
  // settled_cost the positions only: it computes the ring's forces itself);
  // those that take a const z expect them current (z was last evaluated).

  // Cost at z; the gradient too if grad is non-null (entries of unknowns that
  // are not free — fixed, inactive — are set to zero; entries owned by other
  // ranks are not meaningful).
  CostTerms evaluate(double* z, double* grad);

  // Reference gradient by central differences, unknown by unknown, each from
  // the cost of the patch of the mesh it can change (the paper's approach).
  // One rank only (its windows reach further than the ghost ring).
  CostTerms numeric_gradient(double* z, double* grad);

  // Whether evaluate(z, grad) runs in one parallel region (on from the
  // start): the cost's element and particle passes, the residuals' halo and
  // the hanging particles' on the master thread, the cost's tile sums and
  // the gradient's element and particle passes, with barriers between: one
  // fork and join where separate regions take seven. Off, the separate
  // regions: the same numbers bit for bit
  // (Evaluator.FusedCostGradientIsTheSeparatePasses).
  void fuse_gradient(bool on) { fused_ = on; }

  // evaluate(z, grad) in two halves, the same numbers bit for bit
  // (Evaluator.CostThenGradientIsEvaluate): the cost at z, keeping what the
  // gradient reads (the residuals at z's indices, the elements' slopes);
  // then the gradient at that z, which must not have changed, with no
  // other entry point between. Nonlinear CG's line search costs its trials
  // and takes the gradient of the accepted one only, with no second cost
  // pass. The unfused evaluate(z, grad) is these two.
  CostTerms cost_for_gradient(double* z);
  void gradient_at_last_cost(double* grad);

  // Approximate diagonal of J^T J (cost = 1/2 |residuals|^2): the diagonal
  // scaling of the unknowns. Entries of non-unknowns are set to 1.
  void scaling_diagonal(double* z, double* diag);

  // The three above with the gradient and diagonal in the compact order of
  // this rank's unknowns (compact_size() entries): 3 per free particle in
  // the particle list's order, then one per owned edge, triple and cell in
  // their lists' order. The same numbers as at z's indices, bit for bit
  // (Evaluator.CompactGradientIsTheGridOne): the nonlinear CG's vectors,
  // none of the grid's size.
  CostTerms evaluate_compact(double* z, double* grad) { return evaluate_as(z, grad, true); }
  void gradient_at_last_cost_compact(double* grad) { gradient_as(grad, true); }
  void scaling_diagonal_compact(double* z, double* diag) { diagonal_as(z, diag, true); }
  int64_t compact_size() const { return compact_block(3) + lists_.shears.size(); }
  // Where a block of the compact order starts (0 positions, 1 tensions,
  // 2 moments, 3 shears).
  int64_t compact_block(int b) const {
    const int64_t n[4] = {3 * lists_.particles.size(), lists_.edges.size(), lists_.triples.size(), 0};
    int64_t c = 0;
    for (int k = 0; k < b; ++k) c += n[k];
    return c;
  }

  // --- the Newton solver's view (src/solver/stiffness.cpp) ---
  // hysteresis_forces(z) then evaluate(z, nullptr), bit for bit, in one pass
  // over the elements: each element's strain, band and geometry are computed
  // once instead of twice (a line search trial's whole work). (On several
  // ranks the ring's force slots hold its own results, not the owners':
  // the same numbers, as ranks_agree checks.)
  CostTerms settled_cost(double* z);
  // Whether stiffness_diagonal would read settled_cost's numbers now.
  bool diagonal_reads_settled() const { return settled_; }
  // The strain gradient of the triple (kind 1) or cell (kind 2) at list
  // position pos (the ring's after this rank's): `computed` as a product
  // that keeps nothing computes it from z, `kept` read back from the kept
  // numbers (keeping products, after settled_cost or stiffness_diagonal at
  // z). Tests hold them to the same bits: what a product recomputes from z
  // must be what was kept.
  void element_gradients(int kind, int64_t pos, const double* z, V3<double>* computed, V3<double>* kept) const;
  // Sets every active element force to its hysteresis target (Band::stop) at
  // the positions in z: there the band and memory costs vanish and the cost
  // is the Newton term alone, a function of the positions.
  void hysteresis_forces(double* z);
  // At a step's start: turns the step-start forces (z's force slots) into
  // Band::anchor values, each listed element's (in list order, as the
  // element buffers), with the strains at positions x1 (whose ghost and
  // hanging entries must be current) and the ring's forces in z current.
  // After a list change, an entry point that reads them before this is
  // called computes them from the cloth's x1 and z: they always belong to
  // the present lists. x1 holds particle p at slot[p] (Cloth::slots; null:
  // at p).
  void hysteresis_anchors(const double* x1, const double* z, const int32_t* slot = nullptr);
  // Element slot s's anchor (kind 0 edge, 1 triple, 2 cell); NaN where s is
  // in no list.
  double anchor(int kind, int64_t s) const {
    const std::vector<double>* a[3] = {&anc_e_, &anc_t_, &anc_s_};
    const int64_t pos = position_of(kind, s);
    return pos >= 0 ? (*a[kind])[size_t(pos)] : std::nan("");
  }
  // Each listed triple's bending axis (its own and the ring's) from the
  // positions x1, frozen until the next call: the time loop's at a step's
  // start (ghosts current). After a list change, an entry point that reads
  // them before this is called freezes them from the cloth's x1 (p at
  // slot[p]; null: at p).
  void freeze_bend_axes(const double* x1, const int32_t* slot = nullptr);
  // The listed edges' rest lengths (list order, the ring's after this
  // rank's), laid out for the present lists: grid sequencing's eased edges
  // lengthen and relax them between steps (amrc/sequence.hpp); a list change
  // lays them out again from the mesh.
  double* edge_rest_lengths() {
    list_rows(false);
    return rest_e_.data();
  }
  // Edge slot s's rest length as last laid out; NaN where s is in no list.
  double edge_rest(int64_t s) const {
    const int64_t pos = position_of(0, s);
    return pos >= 0 ? rest_e_[size_t(pos)] : std::nan("");
  }
  // Triple slot s's rest length and cell slot s's area as the kernels
  // compute them (from the neighbours in list order); NaN where s is in no list.
  double triple_rest_of(int64_t s) const {
    const int64_t pos = position_of(1, s);
    return pos >= 0 ? triple_rest(s, pos) : std::nan("");
  }
  double cell_area_of(int64_t s) const {
    const int64_t pos = position_of(2, s);
    return pos >= 0 ? cell_area_at(s, pos) : std::nan("");
  }
  // Triple slot s's axis (3 values), nullptr where s is in no list.
  const double* bend_axis(int64_t s) const {
    const int64_t pos = position_of(1, s);
    return pos >= 0 ? &axis_t_[3 * size_t(pos)] : nullptr;
  }
  // Kv = dr/dx v for the Newton residual r (N) with the forces at their
  // targets: mass, material stiffness, the stretch geometric term and the
  // contact normal term (the indefinite bending/shear geometric terms are
  // left out so that K stays positive definite). v and K v laid out like
  // z's positions (tests, tools; Newton calls stiffness_product_local
  // below): written at the free particles' positions (hanging ones': 0).
  // Needs stiffness_diagonal at the same z and lists first (Newton's linear
  // CG calls it once per solve): it reads the band slopes that call froze.
  void stiffness_product(const double* z, double* v, double* kv);
  // Whether stiffness_product keeps its z-only numbers across a linear
  // solve (46 doubles a listed particle; K's 7 frozen slopes and tensions
  // a particle are then not held: the kept numbers carry them; on from the
  // start): off, every product computes them again, the same numbers
  // (bench_gradient's BM_KeptProducts times both). Allocates: call it
  // before the time loop.
  void keep_products(bool on);
  // Whether the Newton solver's numbers (the kept ones above, or K's frozen
  // slopes and tensions) are held at all: on from the start; a nonlinear CG
  // run, which never reads them, turns it off (TimeLoop) and holds neither.
  // A stiffness entry point turns it on again (allocating).
  void hold_stiffness(bool on);
  // Newton through the bands' kinks (band_active_set.hpp): on, every
  // evaluation notes each band element's strain, force and branch.
  // Allocates: call it before the time loop.
  void track_branches(bool on);
  BandActiveSet& branches() { return active_; }
  // Right after settled_cost at z: each element that changed branch at the
  // last trial gets its secant as K's band slope; how many did (this rank's,
  // the ring's included).
  int64_t kink_tangents();
  // Its diagonal, at the same entries. Also freezes each element's band
  // slope (and each edge's tension) at z for stiffness_product, so that a
  // product evaluates no band, power law or angle: those cost more than the
  // product's own arithmetic, once per product. Right after settled_cost at
  // the same z (Newton's order), it reads that pass's numbers: the same
  // diagonal, bit for bit, without the elements' geometry; else it computes
  // them. Either way, keeping products, it leaves every number the products
  // read kept (the particles' contact ones too).
  void stiffness_diagonal(const double* z, double* diag);
  // The same two with v, K v and the diagonal in the rank's own numbering
  // (numbering(): 3 values a particle, local_size() particles; the free
  // ones first, in the compact vectors' order): what Newton's linear CG
  // calls, with no vector of the grid's size. Results at the free
  // particles' entries (hanging ones': 0, or 1 on the diagonal); v's
  // hanging and ghost entries are written (interpolated, received), its
  // other entries not free here must hold 0. The two above go through
  // these (allocating: not for a step).
  void stiffness_product_local(const double* z, double* v, double* kv);
  void stiffness_diagonal_local(const double* z, double* diag);
  // The numbering for the present lists (held from the first call of this
  // or the two above, as a CG run never needs it; then built at
  // fit_to_lists, else at the first entry point after a list change), its
  // size and the room a solver's local vectors should have: enough for any
  // lists up to the next fit_to_lists.
  const LocalNumbering& numbering() {
    list_rows(false);
    use_local();
    return local_;
  }
  int64_t local_size() { return numbering().size(); }
  size_t local_capacity() const { return rows_.capacity() + local_.others_capacity(); }

  // K assembled as 3 x 3 blocks over this rank's free particles, row r for
  // lists().particles.items[r] (the compact vectors' order), hanging
  // particles folded onto their ends (P^T K P) as in stiffness_product:
  // the same operator, summed in another order. Reads the numbers
  // stiffness_diagonal kept at z (call it first). Columns of particles this
  // rank does not own are left out (one rank sees the whole operator),
  // unless `column_of` (grid particle -> column, of every rank's free
  // particles; `columns` of them) numbers them: K's rows as one rank
  // assembles them, for a multigrid built from every rank's rows. The
  // pattern is kept while the lists and `column_stamp` stay.
  void assemble_stiffness(BlockMatrix& K, const std::vector<int32_t>* column_of = nullptr, int64_t columns = 0,
                          uint64_t column_stamp = 0);

  // Newton residual (scaled) of the last evaluation, 3 per free particle in
  // the particle list's order (lists().particles.items[r] at 3 r): the
  // compact vectors' order (Newton reads it as its right-hand side).
  const std::vector<double>& residual() const { return rho_; }
  // The same at z's position indices, with the ghosts' (from their owners)
  // and the hanging particles' (their ends', interpolated): what the
  // gradient's element passes read. Held only once a gradient was asked for
  // (empty in Newton's runs); the last evaluate() with a gradient's.
  const std::vector<double>& gradient_residual() const { return rho_grid_; }

  const ActiveLists& lists() const { return lists_; }
  // The arrays indexed by list position (element buffers, kept numbers,
  // band costs and slopes, neighbours, rows) hold the lists' elements only:
  // this rank's and its ring's, on the present mesh. After the lists were
  // rebuilt, between steps: grows them where the lists outgrew them (a
  // refinement, a migration; else the first evaluation would, inside a
  // step) and keeps their capacity where the lists shrank (AMRC coarsening:
  // no allocation); with `exact` (grid sequencing's next stage) sizes them
  // to the lists, shrinking too.
  void fit_to_lists(bool exact);
  // The rows' capacity: free and hanging particles the arrays have room for
  // (the Newton solver's compact vectors follow it).
  size_t row_capacity() const { return rows_.capacity(); }
  // Cloth-cloth contact's pair list (Model::self_contact).
  const SelfContact& self_contact() const { return self_; }
  // Its arrays' capacities.
  void memory(MemoryTable& t) const;
  // Puts AMRC's hanging particles (3 values per particle in x) on their
  // coarse sides; the entry points above do it to z themselves. With
  // `slot`, x holds p at slot[p] (Cloth::slots), and a link whose particles
  // are not all held is left: nothing on this rank reads it.
  void interpolate_hanging(double* x, const int32_t* slot = nullptr) const;
  double force_scale() const { return m_.force_scale; }

 private:
  // Element kernels: slot s at position pos of its list (the ring's after
  // this rank's), which places its buffer entries (see rows_).
  // With settle (z itself), the element's force there is first set to its
  // hysteresis target at z's positions (settled_cost).
  void edge_forces(int64_t s, int64_t pos, const double* z, double* settle = nullptr);
  // A run of the edges' list, four edges' lengths at a time (EdgeFour).
  void edge_forces(const ItemRun& run, const double* z, double* settle);
  // The edge's band, force and cost from its length L and its gradient g.
  void edge_band(int64_t s, int64_t pos, double L, const V3<double> g[2], const double* z, double* settle);
  // The same for the four edges at run positions k..k+3 (lengths L,
  // gradients g), the band's arithmetic in lanes (band_K.hpp; with
  // DRAPE_LANES): edge_band's numbers bit for bit.
  void edge_bands(const ItemRun& run, int64_t k, const double L[4], const V3<double> g[4][2], const double* z,
                  double* settle);
  // The four edges at run positions k..k+3: their ends' positions, their ends.
  void edge_four(const ItemRun& run, int64_t k, const double* z, EdgeFour& e, int64_t ends[4][2]) const;
  void triple_forces(int64_t s, int64_t pos, const double* z, double* settle = nullptr);
  // A run of the triples' list, four triples' angles at a time (TripleFour).
  void triple_forces(const ItemRun& run, const double* z, double* settle);
  // The triple's band, force and cost from its rest length Lm, its angle th
  // and its gradient g.
  void triple_band(int64_t s, int64_t pos, double Lm, double th, const V3<double> g[3], const double* z,
                   double* settle);
  // The four triples at run positions k..k+3 (particles ids, angles th,
  // gradients g), likewise: triple_band's numbers bit for bit.
  void triple_bands(const ItemRun& run, int64_t k, const int64_t ids[4][3], const double th[4],
                    const V3<double> g[4][3], const double* z, double* settle);
  // The four triples at run positions k..k+3: their positions and axes, their particles.
  void triple_four(const ItemRun& run, int64_t k, const double* z, TripleFour& t, int64_t ids[4][3]) const;
  void shear_forces(int64_t s, int64_t pos, const double* z, double* settle = nullptr);
  // A run of the cells' list: with DRAPE_LANES four cells' angles and bands
  // at a time (shear_angles_four, shear_bands), shear_forces' numbers bit
  // for bit; else cell by cell.
  void shear_forces(const ItemRun& run, const double* z, double* settle);
  // The four cells at run positions k..k+3 (areas A, angles phi, gradients g).
  void shear_bands(const ItemRun& run, int64_t k, const double A[4], const double phi[4], const V3<double> g[4][4],
                   const double* z, double* settle);
  CostTerms cost_pass(double* z, double* settle, bool grid);
  void size_slopes();
  // Sizes the arrays kept in list order (and the rows) for the lists now:
  // grown where a list outgrew them (with an eighth to spare), else kept;
  // with `exact`, to the lists' sizes (shrunk too). Their contents are
  // rewritten before they are read (rows and neighbours by list_rows).
  void fit_arrays(bool exact);
  void fit_slopes(bool exact);
  bool slopes_ = false;  // the gradient's slopes are held (size_slopes)
  // An element's stiffness numbers at z (edge_kept's, kept_gradients'),
  // its band stop computed here; its frozen tension and slope recorded
  // (an edge's kept, or in K's frozen slopes and tensions: edge_stiffness_at
  // reads them back).
  void edge_numbers(int64_t s, int64_t pos, const double* z);
  void triple_numbers(int64_t s, int64_t pos, const double* z, double* kg);
  void shear_numbers(int64_t s, int64_t pos, const double* z, double* kg);
  // The Newton residual's coefficients of the step (each a division),
  // computed once a pass rather than once a particle.
  struct InertiaTerms {
    double accel, ratio, drag, inv_scale, inertia;
  };
  InertiaTerms inertia_terms() const {
    return {m_.accel_coeff(), m_.dt / m_.dt_prev, m_.drag / m_.dt, 1.0 / m_.force_scale, m_.inertia_coeff()};
  }
  // Particle p's (at list position pos) scaled residual into rho (3);
  // returns its Newton cost.
  double particle_residual(int64_t p, int64_t pos, const GatherRow& row, const double* z, double* rho,
                           const InertiaTerms& it, const double* passed);
  // The force hanging particles pass on to the particle at list position
  // pos (zeros where none; nullptr without hanging links).
  const double* passed_force(int64_t pos) const {
    static const double none[3] = {0, 0, 0};
    if (lists_.hanging.empty()) return nullptr;
    return pos >= 0 && row_hslot_[size_t(pos)] >= 0 ? &hres_[3 * size_t(row_hslot_[pos])] : none;
  }
  void edge_gradient(int64_t s, int64_t pos, const double* z, double* grad);
  void edge_gradient(const ItemRun& run, const double* z, double* grad);
  void edge_gradient_out(int64_t s, int64_t pos, const V3<double>& ra, const V3<double>& rb, const V3<double> g[2],
                         const V3<double>& hv, const double* z, double* grad);
  void triple_gradient(int64_t s, int64_t pos, const double* z, double* grad);
  void triple_gradient(const ItemRun& run, const double* z, double* grad);
  // The triple's buffer entries and force gradient from its particles'
  // residuals r, its angle's gradient g and H r.
  void triple_gradient_out(int64_t s, int64_t pos, const V3<double> r[3], const V3<double> g[3],
                           const V3<double> hr[3], const double* z, double* grad);
  void shear_gradient(int64_t s, int64_t pos, const double* z, double* grad);
  // A run of the cells' list: with DRAPE_LANES four cells side by side
  // (shear_gradient_four: shear_cells_hv_four), shear_gradient's numbers
  // bit for bit; else cell by cell.
  void shear_gradient(const ItemRun& run, const double* z, double* grad);
  void shear_gradient_four(const ItemRun& run, int64_t k, const double* z, double* grad);
  void particle_gradient(int64_t p, int64_t pos, const GatherRow& row, const double* z, double* grad,
                         const InertiaTerms& it);
  // The entry points above, the gradient or diagonal at z's indices or in
  // the compact order (compact_ while they run).
  CostTerms evaluate_as(double* z, double* grad, bool compact);
  void gradient_as(double* grad, bool compact);
  void diagonal_as(double* z, double* diag, bool compact);
  bool compact_ = false;
  int64_t gradient_size() const;
  template <class F>
  void for_each_unknown_entry(double* out, F&& f);
  // Where the element at list position pos of kind (0 edge, 1 triple,
  // 2 cell), slot s, keeps its force's entry in the gradient or diagonal;
  // null for the ring's in the compact order (other ranks' unknowns).
  double* force_entry(double* out, int kind, int64_t s, int64_t pos) const {
    if (!compact_) return out + c_.force_index(kind, s);
    const ActiveList* own[3] = {&lists_.edges, &lists_.triples, &lists_.shears};
    return pos < own[kind]->size() ? out + compact_block(kind + 1) + pos : nullptr;
  }
  // A free particle's first entry: its position in z, or 3 x its place in
  // the particle list (-1 where it is not this rank's: a ghost).
  int64_t particle_entry(int64_t p) const;
  int64_t list_position(int64_t p) const;  // p's in lists_.particles (-1: not listed)
  int64_t particle_entry(int64_t p, int64_t pos) const { return compact_ ? 3 * pos : 3 * p; }
  // Element passes: this rank's elements, then the ghost ring's (split in
  // chunks as active lists whatever the schedule: the ring has no tiles).
  template <class F>
  void for_elements(const ActiveList& owned, const ActiveList& ring, F&& f) {
    for_each_item(owned, pol_, f);
    if (ring.size() > 0) for_each_item(ring, LoopPolicy{Schedule::ActiveLists, 1}, f, owned.size());
  }
  template <class F>
  void for_edges(F&& f) { for_elements(lists_.edges, lists_.ring_edges, f); }
  template <class F>
  void for_triples(F&& f) { for_elements(lists_.triples, lists_.ring_triples, f); }
  template <class F>
  void for_shears(F&& f) { for_elements(lists_.shears, lists_.ring_shears, f); }
  // The three element passes (this rank's and the ring's) in one parallel
  // region, and, with a particle pass, after a barrier, `between` on one
  // thread (serial work such as the hanging particles') and the particle
  // pass that gathers the elements' results: one fork and join
  // instead of up to seven (on a coarse mesh a pass is microseconds of work).
  // `between` may run on any thread of the team: it must not call MPI (the
  // library runs FUNNELED), throw, or contain OpenMP work-sharing.
  template <class FE, class FT, class FS>
  void element_passes(FE&& fe, FT&& ft, FS&& fs) {
    passes(fe, ft, fs, [] {}, static_cast<std::nullptr_t*>(nullptr));
  }
  template <class FE, class FT, class FS, class Between, class FP>
  void elements_then_particles(FE&& fe, FT&& ft, FS&& fs, Between&& between, FP&& fp) {
    passes(fe, ft, fs, between, &fp);
  }
  template <class FE, class FT, class FS, class Between, class FP>
  void passes(FE& fe, FT& ft, FS& fs, Between&& between, FP* fp);
  // The cuts of three element bodies' passes over the owned lists and the
  // ring's, in element_loops' order (edges, the ring's, triples, ...);
  // serial, before their region.
  template <class FE, class FT, class FS>
  void element_cuts(ListCuts* cuts[6]);
  // Inside a region: the three element passes, this rank's and the ring's.
  template <class FE, class FT, class FS>
  void element_loops(FE& fe, FT& ft, FS& fs, ListCuts* const cuts[6]);
  // After the region: cuts[0..n) (element_cuts' order, then the particles')
  // follow the times measured; the ring's always (active lists), the
  // owned lists' with that schedule. Null entries are skipped.
  void rebalance(ListCuts* const* cuts, int n) const;
  // evaluate(z, grad) in one parallel region (fuse_gradient).
  CostTerms fused_cost_gradient(double* z, double* grad);
  bool fused_ = true;
  // The z of the last cost_for_gradient until its gradient is taken or
  // evaluate or settled_cost overwrites its numbers (null: none to take).
  const double* cost_z_ = nullptr;
  template <class Visit>
  void for_gathered(int64_t p, Visit&& visit) const;
  // The row's entries summed into out (3), in for_gathered's order: forces,
  // gradients, K v. Written out, no lambdas passed: the particle passes'
  // inner loop (through lambdas the product's loop no longer inlined it,
  // 9-18 % slower).
  void gather_vector(const GatherRow& row, double out[3]) const {
    if (narrow_)
      gather_vector_as<true>(row, out);
    else
      gather_vector_as<false>(row, out);
  }
  template <bool Narrow>
  void gather_vector_as(const GatherRow& row, double out[3]) const;
  // Their diagonals summed into sum (an edge's is the same at both ends;
  // narrow, a triple's and a cell's from the kept numbers).
  void gather_diagonal(const GatherRow& row, double& sum) const;
  // p's row (any active particle: the hanging ones, which have no place in
  // the particle list, too); false if one of its elements is in no list,
  // left out of the row. That happens only to a hanging particle far from
  // this rank's tiles, whose result, like any entry this rank does not own,
  // is not meaningful and reaches no owned entry.
  bool listed_row(int64_t p, GatherRow& row) const;
  // The same, the slots found by `walk` (the particles in list order: fast).
  bool listed_row(int64_t p, GatherRow& row, ListWalk& walk) const;
  GatherRow row_of(int64_t p) const {
    GatherRow r;
    listed_row(p, r);
    return r;
  }
  // Hanging particle i's (of lists_.hanging): kept after the particle list's.
  const GatherRow& hanging_row(size_t i) const { return rows_[lists_.particles.size() + i]; }
  // Refreshes rows_, the neighbours and the rest geometry when the lists have changed (and,
  // with `derive`, the axes and anchors where a list change left them stale).
  void list_rows(bool derive = true);
  void build_rows();
  void place_neighbours();  // nb_e_ (and without local_on_ nb_t_, nb_s_) for the present lists
  bool axes_stale_ = false, anchors_stale_ = false;
  CostTerms reduce_costs();
  // reduce_costs' tile sums into partials_, inside a region; then the sum
  // of the tiles' (across ranks), after it.
  void cost_tile_loops();
  CostTerms sum_cost_tiles();
  // AMRC's hanging particles (ActiveLists::hanging), serial and in a fixed
  // order: the element forces on them into their ends' residuals; residuals
  // back onto them; per-particle results (the gradient, K v, diagonals) onto
  // their ends.
  void hanging_forces(const double* z);
  void hanging_residuals();
  // Each link's h, a and b their slots in hres_ and hpend_ (the hanging
  // particles' first, by link; the other ends after), and each particle
  // row's slot (-1: none). At list changes only.
  void number_hanging_slots();
  void hanging_gradient(const double* z, double* grad);
  template <class Own>
  void hanging_into_ends(double* out, Own&& own, double power, double fill);
  // The same two for vectors in the own numbering (own(h, l, row, v): h's
  // grid id, its local index).
  void interpolate_hanging_local(double* x) const;
  template <class Own>
  void hanging_into_ends_local(double* out, Own&& own, double power, double fill);
  // The numbering, the elements' local tables, the hanging links' and the
  // halo's local indices, for the lists, hanging particles and halo plan now.
  void build_local(bool exact);
  void number_pairs();
  void number_elements(bool exact);
  void map_hanging(bool exact);
  void map_halo(bool exact);
  void use_local();  // from now on: held and kept current
  void fit_local_tables(bool exact);
  bool local_on_ = false;
  bool local_stale() const {
    return local_stamp_ != lists_.stamp || lists_.stamp == 0 || local_hanging_ != lists_.hanging.size() ||
           local_plan_ != halo_.plan_version();
  }
  // Calls f(k, id) for each particle (its k-th) of the element at pos.
  template <class F>
  void edge_particles(int64_t s, F&& f) const {
    f(0, s >> 1);
    f(1, c_.next_at(s & 1, s >> 1));
  }
  template <class F>
  void triple_particles(int64_t s, F&& f) const {
    f(0, c_.prev_at(s & 1, s >> 1));
    f(1, s >> 1);
    f(2, c_.next_at(s & 1, s >> 1));
  }
  template <class F>
  void cell_particles(int64_t s, F&& f) const {
    f(0, s);
    for (int k = 0; k < 3; ++k) f(k + 1, c_.cell_at(k, s));
  }
  void clear_hanging(std::vector<double>& a);
  double window_cost(const double* z, int ic, int jc);

  const Cloth& c_;
  const Model& m_;
  const ActiveLists& lists_;
  const Tiling& tiling_;
  const LoopPolicy& pol_;
  const Reducer& red_;
  const Halo& halo_;
  static_assert(kShearSlot == 12 && kTripleSlot == 9, "buffer slots: 3, 4 particles x 3");
  // An edge's contributions to its ends are each other's negatives (its
  // strain's gradient is -u, u, and every pass's contribution is linear in
  // it), negated exactly: its buffer holds its second end's (3 doubles),
  // which the first end gathers negated, or, for a diagonal, as it is.
  static constexpr int kEdgeEntry = 3;
  std::vector<double> buf_e_, buf_t_, buf_s_;     // per-element contributions to particles (3, 9, 12), list order
  // Narrow (keeping products, no gradient or scaling diagonal asked for:
  // Newton's runs), a triple's and a cell's buffer holds one number c, its
  // contribution to its k-th particle being c times the kept gradient g_k
  // (the residual's force times width or area, K v's stiffness along the
  // gradients); the diagonal of K reads the kept numbers alone. A
  // gradient's contributions (a force times the gradient's derivative plus
  // a slope times the gradient) and the scaling diagonal's are no multiple
  // of one vector: the first such entry point widens them for good (wide_).
  bool wide_ = false, narrow_ = false;  // narrow_: keep_ && !wide_, as fit_arrays sized them
  void widen();
  std::vector<double> cost_p_;                    // Newton cost per free particle, list order
  // Per element, in list order like buf_*: a coarse mesh's elements lie far
  // apart in grid order, one cache line each per array.
  std::vector<double> cost_e_, cost_t_, cost_s_;  // band cost
  std::vector<double> gq_e_, gq_t_, gq_s_;        // band cost slope along dk/dx
  std::vector<double> gf_e_, gf_t_, gf_s_;        // band cost derivative wrt the element force
  std::vector<double> rho_;                       // scaled Newton residual, 3 per free particle, list order
  std::vector<double> rho_grid_;                  // the same at z's indices, ghosts too (gradients only)
  std::vector<double> k_slope_e_, k_slope_t_, k_slope_s_;  // K's frozen band slopes, list order (not keeping)
  std::vector<double> k_tension_;                 // and edge tensions
  // stiffness_product's numbers kept (keep_products) by list position:
  // edges (edge_kept: the frozen tension and slope alone, the geometry read
  // from z again), triples (kept_bend: slope factor, two gradients) and
  // cells (slope factor, then the gradient, 4 x 3). What is cheaper to read
  // from z than from memory is computed by each product: an edge's
  // direction and length, a particle's contact (kKc: force, size, slope).
  // Kept by settled_cost, or by a diagonal at a z no settled_cost saw (or,
  // after a list change, by the next product); kg_ready_ while they are the
  // linear solve's z's.
  static constexpr int kKgEdge = 2, kKgTriple = kKeptBend, kKgCell = 13, kKc = 5;
  // settled_cost keeps the elements' numbers (settled_, until another
  // evaluation, new anchors or a list change): they are its band stops and gradients, so
  // stiffness_diagonal at the same z reads them instead of computing the
  // elements' strains, bands and angles a third time.
  bool keep_ = false;
  bool keep_wanted_ = true;  // keep_products' setting; keep_ is it while stiffness_ holds
  bool stiffness_ = true;    // hold_stiffness
  bool kg_ready_ = false;
  bool settled_ = false;
  std::vector<double> kg_e_, kg_t_, kg_s_;
  // Per free particle (list order), kept beside them: whether the obstacle,
  // the floor or friction acts on it at the diagonal's z (1) or nothing
  // does (0): the products then skip its contact and friction terms, which
  // would add nothing, and their reads of z and x1 at its grid id.
  std::vector<uint8_t> touch_;
  // And its mass, read in list order by the products, not at the grid id (a
  // coarse stage's particles lie a cache line apart there).
  std::vector<double> mass_k_;
  // An edge's kept numbers into ke: its frozen tension and slope / rest
  // length. Its direction and length are z's, its width the rest
  // geometry's: computed or read where used (edge_stiffness_at), not held.
  static void edge_kept(double tension, double slope_per_rest, double* ke) {
    ke[0] = tension;
    ke[1] = slope_per_rest;
  }
  // An edge's stiffness numbers at z (edge_K.hpp): its ends' positions with
  // the frozen tension and slope (kept, or K's frozen slopes and tensions).
  EdgeStiffness edge_stiffness_at(int64_t s, int64_t pos, const double* z) const {
    const EdgeStiffness f = edge_frozen(pos);
    const int64_t p = s >> 1, q = edge_far(pos);
    return edge_stiffness(load3<double>(z + 3 * p), load3<double>(z + 3 * q), f.tension, f.slope_per_rest, f.width);
  }
  // Its frozen tension and slope / rest length and its width alone.
  EdgeStiffness edge_frozen(int64_t pos) const {
    const size_t i = size_t(pos);
    const double tension = keep_ ? kg_e_[kKgEdge * i] : k_tension_[i];
    const double slope = keep_ ? kg_e_[kKgEdge * i + 1] : k_slope_e_[i] / rest_e_[i];
    return {{0, 0, 0}, 0, tension, slope, width_e_[i]};
  }
  // stiffness_product's edges: each one's contribution to its second end.
  void edge_products(const ItemRun& run, const double* z, const double* v);
  // A cell's: the slope factor, then the n gradients (a triple's: kept_bend).
  template <class V>
  static void kept_gradients(double factor, const V* g, int n, double* kg) {
    kg[0] = factor;
    for (int k = 0; k < n; ++k) {
      kg[1 + 3 * k] = g[k].x;
      kg[2 + 3 * k] = g[k].y;
      kg[3 + 3 * k] = g[k].z;
    }
  }
  // A particle's contact numbers into kc (see kKc), at z.
  void contact_terms(int64_t p, const double* z, double* kc) const;
  // Friction's block (contact.hpp) times v_p into out: computed, not kept
  // (x1 and z give it); assemble_stiffness reads it at k_z_, the z of the
  // last stiffness_diagonal.
  void add_friction_product(int64_t p, const double* z, const double* vp, double* out) const;
  const double* k_z_ = nullptr;
  // The element buffers (and stiffness_product's z-only numbers) are in
  // list order: an element's at its position in its list (the ring's after
  // this rank's), so on a coarse AMRC mesh, whose slots lie far apart, an
  // element pass streams through them and a particle finds its elements'
  // entries on nearby lines. rows_: each owned particle's entries (by its
  // position in the particle list), then each hanging particle's
  // (hanging_row), for rows_stamp_'s lists and rows_hanging_ hanging
  // particles. Sized by the lists (fit_arrays): on several ranks, or on a
  // coarse mesh, they hold this rank's elements only. No map by slot: the
  // rows' slots are found by walking the lists (ListWalk), any other's by a
  // search in its list (position_of).
  std::vector<GatherRow> rows_;
  // Slot s of kind (0 edge, 1 triple, 2 cell): its position, -1 in no list.
  int64_t position_of(int kind, int64_t s) const;
  // The neighbour tables' entries each element reads, in list order too:
  // an edge's far end, a triple's previous and next particles, a cell's
  // corners 1-3 (the tables' own lines are one per element on a coarse mesh).
  // The triples' and cells' only while there is no own numbering
  // (local_on_: a nonlinear CG run): with it, their local indices (lo_t_,
  // lo_s_) name the same particles, their grid ids one lookup away (28 bytes
  // a particle fewer in Newton's runs). The edges' stay: each product reads
  // an edge's far end in z, and the lookup there costs it a tenth.
  std::vector<int32_t> nb_e_, nb_t_, nb_s_;
  // The grid id of own-numbering index l: the free particles' come first,
  // in the particle list's order.
  int64_t local_id(int32_t l) const {
    const ActiveList& pl = lists_.particles;
    return l < pl.size() ? pl.items[size_t(l)] : local_.id_of(l);
  }
  // An edge's far end, a triple's previous (end 0) and next (end 1)
  // particles, a cell's corner k + 1, of the element at pos.
  int64_t edge_far(int64_t pos) const { return nb_e_[size_t(pos)]; }
  int64_t triple_end(int64_t pos, int end) const {
    return local_on_ ? local_id(lo_t_[3 * size_t(pos) + 2 * end]) : nb_t_[2 * size_t(pos) + end];
  }
  int64_t cell_corner(int64_t pos, int k) const {
    return local_on_ ? local_id(lo_s_[4 * size_t(pos) + k + 1]) : nb_s_[3 * size_t(pos) + k];
  }
  // Each triple's bending axis (3 doubles), in list order too.
  std::vector<double> axis_t_;
  // Each element's rest geometry (mesh/topology.hpp), in list order too:
  // edges' rest lengths and widths, triples' widths. Laid out when the lists
  // change (rest_stamp_ their stamp), kept until then: grid sequencing eases
  // edges' rest lengths in between. A triple's rest length and a cell's area
  // are computed from the neighbours (triple_end, cell_corner), exactly as the
  // mesh computes them: 24 bytes a particle fewer, a few operations more.
  std::vector<double> rest_e_, width_e_, width_t_;
  uint64_t rest_stamp_ = 0;
  void lay_out_rest();
  double triple_rest(int64_t s, int64_t pos) const {
    return triple_rest_length(c_.grid, int(s & 1), triple_end(pos, 0), s >> 1, triple_end(pos, 1));
  }
  // The slot at an element's position (the ring's after the owned).
  static int64_t slot_at(const ActiveList& own, const ActiveList& ring, int64_t pos) {
    return pos < own.size() ? own.items[size_t(pos)] : ring.items[size_t(pos - own.size())];
  }
  double cell_area_at(int64_t s, int64_t pos) const {
    return cell_area(c_.grid, s, cell_corner(pos, 0), cell_corner(pos, 1));
  }
  // The same from the particles triple_ids and cell_ids found: in Newton's
  // runs each end is two lookups (local index, then grid id), not to be
  // made twice an element.
  double triple_rest_of(int64_t s, const int64_t ids[3]) const {
    return triple_rest_length(c_.grid, int(s & 1), ids[0], ids[1], ids[2]);
  }
  double cell_area_of(const int64_t ids[4]) const { return cell_area(c_.grid, ids[0], ids[1], ids[2]); }
  // Each element's band anchor (hysteresis_anchors), in list order too.
  std::vector<double> anc_e_, anc_t_, anc_s_;
  BandActiveSet active_;  // the elements' branches (off unless track_branches)
  uint64_t derived_stamp_ = 0;  // the lists the axes and anchors were laid out for
  void triple_ids(int64_t s, int64_t pos, int64_t ids[3]) const {
    ids[0] = triple_end(pos, 0);
    ids[1] = s >> 1;
    ids[2] = triple_end(pos, 1);
  }
  void cell_ids(int64_t s, int64_t pos, int64_t ids[4]) const {
    ids[0] = s;
    for (int k = 0; k < 3; ++k) ids[k + 1] = cell_corner(pos, k);
  }
  // A triple's and a cell's strain gradients at z, as the products that
  // keep nothing compute them.
  void triple_gradients(int64_t s, int64_t pos, const double* z, V3<double> g[3]) const;
  void cell_gradients(int64_t s, int64_t pos, const double* z, V3<double> g[4]) const;
  // The strains the bands read (stiffness.cpp), of the element at pos; x
  // holds p at slot[p] (null: at p).
  double edge_strain_at(const double* x, int64_t s, int64_t pos, const int32_t* slot = nullptr) const;
  double triple_curvature_at(const double* x, int64_t s, int64_t pos, const int32_t* slot = nullptr) const;
  double shear_strain_at(const double* x, int64_t s, int64_t pos, const int32_t* slot = nullptr) const;
  // assemble_stiffness's maps, for asm_stamp_'s lists and the columns of
  // asm_map_columns_: grid particle -> free row (-1 else) and -> hanging
  // index (-1 else); each hanging particle as columns of K and weights
  // (hx_), and per free row the hanging particles leaning on it (ht_,
  // their indices and weights).
  struct HxEntry {
    int32_t row;
    double w;
  };
  void assembly_maps(uint64_t column_stamp);
  uint64_t asm_map_columns_ = 0;
  template <class Add>
  void row_terms(int64_t r, Add&& add) const;
  template <class Columns>
  static void rank_one(const double* kg, int n, int part, const int64_t* ids, double w, Columns&& columns);
  std::vector<int32_t> asm_index_, asm_hang_;
  const int32_t* asm_columns_ = nullptr;  // assemble_stiffness's global columns, while it runs
  std::vector<int64_t> hx_start_, ht_start_;
  std::vector<HxEntry> hx_, ht_;
  uint64_t asm_stamp_ = 0, asm_pairs_ = 0;
  size_t asm_hanging_ = 0;
  bool asm_pattern_ = false;
  PatternScratch asm_scratch_;  // K's pattern rebuilt in kept buffers
  SlotMaps asm_slots_;
  uint64_t rows_stamp_ = 0;
  size_t rows_hanging_ = 0;
  // The own numbering (LocalNumbering) and, in list order, the local index
  // of each element's particles (an edge's 2, a triple's 3 in the order
  // triple_ids gives, a cell's 4 corners): the product reads v there. Per
  // hanging link, h's, a's and b's; per particle the halo's plan sends and
  // receives, its index (-1: none). hpend_lo_: hanging_into_ends_local's
  // results on the way, 3 a local particle (held once there are hanging ones).
  LocalNumbering local_;
  std::vector<int32_t> lo_e_, lo_t_, lo_s_, hang_lo_, halo_send_, halo_recv_;
  std::vector<double> hpend_lo_;
  uint64_t local_stamp_ = 0, local_plan_ = 0;
  uint64_t pairs_numbered_ = 0;  // the pair list (SelfContact::builds) whose partners number_pairs kept
  int64_t pairs_missing_ = 0;    // its partners the numbering lacks (a product then refuses)
  size_t local_hanging_ = 0;
  std::vector<double> hres_, hpend_;              // hanging links' forces and results on the way to their ends, 3 a slot
  std::vector<int32_t> hslot_, row_hslot_;         // slots: 3 a hanging link; one a particle row
  std::vector<std::pair<int64_t, int32_t>> hsort_;  // the links' particles by id, numbering the slots
  std::vector<double> partials_;                  // 4 rows x owned tiles
  std::vector<double> zwork_;                     // numeric gradient's perturbed copy
  // Self-contact's pairs, made to hold at z by every entry point that
  // starts at a new z (evaluate, settled_cost, both diagonals), before its
  // exchange of positions: a new list's contact ghosts come with it.
  // Returns whether the list was built again.
  SelfContact self_;
  bool refresh_pairs(const double* z) {
    return m_.self_contact && self_.refresh(c_, lists_.particles, lists_.stamp, m_.contact, z, red_, halo_);
  }
};

// The element buffer entries particle p gathers, always in the same order:
// this fixed order is what makes the sums reproducible. visit(place, kind,
// slot, part): place 0-13 in that order (GatherRow), kind 0 edge, 1 triple,
// 2 shear cell, and p's part in the element (its 3 doubles at 3 part).
template <class Visit>
void Evaluator::for_gathered(int64_t p, Visit&& visit) const {
  for (int d = 0; d < 2; ++d) {
    const int64_t pv = c_.prev_at(d, p), nx = c_.next_at(d, p);
    const int at = GatherRow::kPerDirection * d;
    if (c_.edge_on_at(2 * p + d)) visit(at, 0, 2 * p + d, 0);
    if (pv >= 0 && c_.edge_on_at(2 * pv + d)) visit(at + 1, 0, 2 * pv + d, 1);
    if (nx >= 0 && c_.triple_on_at(2 * nx + d)) visit(at + 2, 1, 2 * nx + d, 0);
    if (c_.triple_on_at(2 * p + d)) visit(at + 3, 1, 2 * p + d, 1);
    if (pv >= 0 && c_.triple_on_at(2 * pv + d)) visit(at + 4, 1, 2 * pv + d, 2);
  }
  if (c_.shear_on_at(p)) visit(GatherRow::kShear, 2, p, 0);
  // p as corner 1, 2, 3 (along i, along j, across) of the cells below it.
  for (int k = 0; k < 3; ++k) {
    const int64_t q = c_.corner_at(k, p);
    if (q >= 0) visit(GatherRow::kShear + k + 1, 2, q, k + 1);
  }
}

// Row entries of a triple (places 2-4 of a direction: its parts 0-2) and a
// cell (kShear + k: its part k) are the element's list position; the wide
// buffers' offsets follow from it.
inline int64_t wide_triple(int32_t pos, int part) { return int64_t(kTripleSlot) * pos + 3 * part; }
inline int64_t wide_cell(int32_t pos, int part) { return int64_t(kShearSlot) * pos + 3 * part; }

// gather_vector's walk, the triples' and cells' contributions read from
// the wide buffers or, narrow, their one number times the kept gradient:
// the element passes' own product, so the same numbers bit for bit.
template <bool Narrow>
inline void Evaluator::gather_vector_as(const GatherRow& row, double out[3]) const {
  const int32_t* at = row.at;
  const double *e = buf_e_.data(), *t = buf_t_.data(), *s = buf_s_.data();
  const double *kt = kg_t_.data(), *ks = kg_s_.data();
  const auto add = [out](const double* c) {
    out[0] += c[0];
    out[1] += c[1];
    out[2] += c[2];
  };
  const auto add_times = [out](double c, const V3<double>& g) {
    out[0] += c * g.x;
    out[1] += c * g.y;
    out[2] += c * g.z;
  };
  for (int d = 0; d < 2; ++d, at += GatherRow::kPerDirection) {
    if (at[0] >= 0) {  // out - c is out + (-c): the first end's entry's sum, bit for bit
      out[0] -= e[at[0]];
      out[1] -= e[at[0] + 1];
      out[2] -= e[at[0] + 2];
    }
    if (at[1] >= 0) add(e + at[1]);
    for (int k = 0; k < 3; ++k) {
      const int32_t pos = at[2 + k];
      if (pos < 0) continue;
      if constexpr (Narrow)
        add_times(t[pos], kept_bend_gradient(kt + int64_t(kKgTriple) * pos, k));
      else
        add(t + wide_triple(pos, k));
    }
  }
  for (int k = 0; k < 4; ++k) {
    const int32_t pos = at[k];
    if (pos < 0) continue;
    if constexpr (Narrow)
      add_times(s[pos], kept_cell_gradient(ks + int64_t(kKgCell) * pos, k));
    else
      add(s + wide_cell(pos, k));
  }
}

inline void Evaluator::gather_diagonal(const GatherRow& row, double& sum) const {
  const int32_t* at = row.at;
  const double *e = buf_e_.data(), *t = buf_t_.data(), *s = buf_s_.data();
  for (int d = 0; d < 2; ++d, at += GatherRow::kPerDirection) {
    if (at[0] >= 0) sum += e[at[0]];  // an edge's is the same at both ends
    if (at[1] >= 0) sum += e[at[1]];
    for (int k = 0; k < 3; ++k) {
      const int32_t pos = at[2 + k];
      if (pos >= 0) sum += narrow_ ? kept_bend_diagonal_at(&kg_t_[size_t(kKgTriple) * pos], k) : t[wide_triple(pos, k)];
    }
  }
  for (int k = 0; k < 4; ++k) {
    const int32_t pos = at[k];
    if (pos >= 0) sum += narrow_ ? kept_gradient_diagonal(&kg_s_[size_t(kKgCell) * pos], k) : s[wide_cell(pos, k)];
  }
}

template <class FE, class FT, class FS>
void Evaluator::element_cuts(ListCuts* cuts[6]) {
  cuts[0] = &cuts_for<FE>(lists_.edges);
  cuts[1] = &cuts_for<FE>(lists_.ring_edges);
  cuts[2] = &cuts_for<FT>(lists_.triples);
  cuts[3] = &cuts_for<FT>(lists_.ring_triples);
  cuts[4] = &cuts_for<FS>(lists_.shears);
  cuts[5] = &cuts_for<FS>(lists_.ring_shears);
}

template <class FE, class FT, class FS>
void Evaluator::element_loops(FE& fe, FT& ft, FS& fs, ListCuts* const cuts[6]) {
  const LoopPolicy ring{Schedule::ActiveLists, 1};  // the ring has no tiles
  // A body that takes positions counts the ring's on after this rank's.
  item_loops(lists_.edges, pol_, *cuts[0], fe);
  if (lists_.ring_edges.size() > 0) item_loops(lists_.ring_edges, ring, *cuts[1], fe, lists_.edges.size());
  item_loops(lists_.triples, pol_, *cuts[2], ft);
  if (lists_.ring_triples.size() > 0) item_loops(lists_.ring_triples, ring, *cuts[3], ft, lists_.triples.size());
  item_loops(lists_.shears, pol_, *cuts[4], fs);
  if (lists_.ring_shears.size() > 0) item_loops(lists_.ring_shears, ring, *cuts[5], fs, lists_.shears.size());
}

template <class FE, class FT, class FS, class Between, class FP>
void Evaluator::passes(FE& fe, FT& ft, FS& fs, Between&& between, FP* fp) {
  ListCuts* cuts[7] = {};
  element_cuts<FE, FT, FS>(cuts);
  if constexpr (!std::is_same_v<FP, std::nullptr_t>) cuts[6] = &cuts_for<FP>(lists_.particles);
  timed_region([&](RegionTime& rt) {
    element_loops(fe, ft, fs, cuts);
    if constexpr (!std::is_same_v<FP, std::nullptr_t>) {
      const double w0 = omp_get_wtime();
#pragma omp barrier
#pragma omp single
      {
        const double s0 = omp_get_wtime();
        between();
        rt.serial = omp_get_wtime() - s0;
      }
      rt.idle += omp_get_wtime() - w0 - rt.serial;
      item_loops(lists_.particles, pol_, *cuts[6], *fp);
    }
  });
  rebalance(cuts, 7);
}

// Per-particle results at hanging particles (own(h, row, v) computes h's) go to
// their ends with the weights to `power` (1: gradients and K v; 2: diagonals);
// the hanging entries themselves are set to `fill` (0 for a gradient or K v,
// 1 for a diagonal, like every other entry that is not an unknown).
template <class Own>
inline void Evaluator::hanging_into_ends(double* out, Own&& own, double power, double fill) {
  if (lists_.hanging.empty()) return;
  clear_hanging(hpend_);
  for (size_t i = 0; i < lists_.hanging.size(); ++i) {
    const HangingLink& g = lists_.hanging[i];
    const int64_t sh = 3 * int64_t(hslot_[3 * i]), sa = 3 * int64_t(hslot_[3 * i + 1]),
                  sb = 3 * int64_t(hslot_[3 * i + 2]);
    double v[3];
    own(g.h, hanging_row(i), v);
    // pow only for the diagonals: a product's weights are the plain ones.
    const double wa = power == 1.0 ? 1 - g.t : std::pow(1 - g.t, power);
    const double wb = power == 1.0 ? g.t : std::pow(g.t, power);
    for (int k = 0; k < 3; ++k) {
      v[k] += hpend_[sh + k];
      hpend_[sa + k] += wa * v[k];
      hpend_[sb + k] += wb * v[k];
    }
  }
  for (size_t i = 0; i < lists_.hanging.size(); ++i)
    for (int end = 1; end < 3; ++end) {
      const int64_t e = end == 1 ? lists_.hanging[i].a : lists_.hanging[i].b, s = 3 * int64_t(hslot_[3 * i + end]);
      const int64_t o = c_.free(e) ? particle_entry(e) : -1;
      for (int k = 0; k < 3; ++k) {
        if (o >= 0) out[o + k] += hpend_[s + k];
        hpend_[s + k] = 0.0;  // applied once
      }
    }
  if (compact_) return;  // a hanging particle has no entry there
  for (const HangingLink& g : lists_.hanging)
    for (int k = 0; k < 3; ++k) out[3 * g.h + k] = fill;
}

// hanging_into_ends in the own numbering: the same sums in the same order.
template <class Own>
inline void Evaluator::hanging_into_ends_local(double* out, Own&& own, double power, double fill) {
  const std::vector<HangingLink>& hl = lists_.hanging;
  if (hl.empty()) return;
  double* pend = hpend_lo_.data();
  for (size_t i = 0; i < hl.size(); ++i)
    for (int e = 0; e < 3; ++e)
      for (int k = 0; k < 3; ++k) pend[3 * int64_t(hang_lo_[3 * i + e]) + k] = 0.0;
  for (size_t i = 0; i < hl.size(); ++i) {
    const HangingLink& g = hl[i];
    const int64_t lh = hang_lo_[3 * i], la = hang_lo_[3 * i + 1], lb = hang_lo_[3 * i + 2];
    double v[3];
    own(g.h, lh, hanging_row(i), v);
    const double wa = power == 1.0 ? 1 - g.t : std::pow(1 - g.t, power);
    const double wb = power == 1.0 ? g.t : std::pow(g.t, power);
    for (int k = 0; k < 3; ++k) {
      v[k] += pend[3 * lh + k];
      pend[3 * la + k] += wa * v[k];
      pend[3 * lb + k] += wb * v[k];
    }
  }
  for (size_t i = 0; i < hl.size(); ++i)
    for (int e = 1; e < 3; ++e) {
      const int64_t l = hang_lo_[3 * i + e];
      const bool is_free = c_.free(e == 1 ? hl[i].a : hl[i].b);
      for (int k = 0; k < 3; ++k) {
        if (is_free) out[3 * l + k] += pend[3 * l + k];
        pend[3 * l + k] = 0.0;
      }
    }
  for (size_t i = 0; i < hl.size(); ++i)
    for (int k = 0; k < 3; ++k) out[3 * int64_t(hang_lo_[3 * i]) + k] = fill;
}

}  // namespace drape
