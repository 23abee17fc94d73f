//! The stacked residual of [`super`]'s solve: one block per energy term (math.md §4), each
//! assembling its rows of the Jacobian and its terms of Jᵀr in an order that depends only on the
//! mesh and the free set, in fixed chunks (bit-identical at any thread count).

use rayon::prelude::*;

use super::{Energies, LmOptions, Term};
use crate::geometry::gradient::StencilUsers;
use crate::geometry::Geometry;
use crate::mesh::Mesh;
use crate::solve::cg::JacobianRows;
use crate::solve::fabrication::{lock_residual, GradientHinge, HingeKind};
use crate::solve::face_hinge::FaceTurningHinge;
use crate::solve::highlight_term::HighlightTerm;
use crate::solve::smoothness::{edge_residual_scaled, edge_scale};

/// Rows per parallel chunk. Chunks are fixed by the row order alone, and their results are
/// merged in chunk order, so the triplets, Jᵀr and the energies are bit-identical at any thread
/// count (and to a serial run).
const CHUNK: usize = 512;

/// Blocks of at most this many rows are assembled and summed on the calling thread (same
/// chunks, so the same sums): below it, waking the thread pool costs more than it saves
/// (perf on Fig. 12a's 656-vertex brush: 17 % of the time in the kernel's thread switches).
const SEQUENTIAL_ROWS: usize = 8 * CHUNK;

/// One chunk's contributions: the Jacobian's row blocks (free columns and derivatives) and the
/// terms of Jᵀr, in row order.
#[derive(Default)]
struct Local {
    /// Σ|r|² of the chunk's rows, in row order.
    e: f64,
    /// Each pushed entry's Jᵀr term dₑ·r, aligned with the entries of `rows` pushed since the
    /// chunk began (their columns are in `rows.col`).
    g: Vec<f64>,
    /// A row's entries before the free-column filter (reused).
    entries: Vec<(u32, [f64; 2])>,
    /// A one-component row's entries (reused).
    entries1: Vec<(u32, f64)>,
    rows: JacobianRows,
}

impl Local {
    /// Adds one row block: residual `r` and its entries `(vertex, ∂r/∂φ_vertex)`; entries of
    /// fixed vertices are dropped, and so is a block with no free entry.
    #[inline]
    fn push(
        &mut self,
        col_of: &[Option<u32>],
        entries: impl Iterator<Item = (u32, [f64; 2])>,
        r: [f64; 2],
    ) {
        self.e += r[0] * r[0] + r[1] * r[1];
        let before = self.rows.col.len();
        for (v, da) in entries {
            if let Some(a) = col_of[v as usize] {
                self.g.push(da[0] * r[0] + da[1] * r[1]);
                self.rows.col.push(a);
                self.rows.d.push(da);
            }
        }
        if self.rows.col.len() > before {
            self.rows.ptr.push(self.rows.col.len() as u32);
        }
    }
}

/// Accumulates Jᵀr and the Jacobian's row blocks (of up to two residual components). Kept for
/// the whole solve, so its buffers are allocated once.
pub(super) struct Assembler<'a> {
    col_of: &'a [Option<u32>],
    pub(super) g: Vec<f64>,
    pub(super) rows: JacobianRows,
    scratch: Local,
}

impl<'a> Assembler<'a> {
    pub(super) fn new(col_of: &'a [Option<u32>], n: usize) -> Self {
        Assembler {
            col_of,
            g: vec![0.0; n],
            rows: JacobianRows { ptr: vec![0], ..Default::default() },
            scratch: Local::default(),
        }
    }

    /// Empties the rows and zeroes Jᵀr for a new assembly (buffers kept).
    fn reset(&mut self) {
        self.g.iter_mut().for_each(|v| *v = 0.0);
        self.rows.ptr.clear();
        self.rows.ptr.push(0);
        self.rows.col.clear();
        self.rows.d.clear();
    }

    /// Assembles `row(item, push)` for every item: on the calling thread into the accumulator
    /// itself for small blocks, else in parallel chunks merged in order. Either way the rows
    /// come out in item order and Jᵀr's terms are added in item order, so the result is the
    /// same bits at any thread count. Returns the rows' energy Σ|r|², summed by chunks of
    /// [`CHUNK`] rows as [`chunked_sum`] does (so it is the same bits as the block's `energy`).
    fn rows<T: Sync>(
        &mut self,
        items: &[T],
        row: impl Fn(&T, &mut Local, &[Option<u32>]) + Sync,
    ) -> f64 {
        let col_of = self.col_of;
        if items.len() <= SEQUENTIAL_ROWS {
            let mut local = std::mem::take(&mut self.scratch);
            local.g.clear();
            local.rows = std::mem::take(&mut self.rows);
            let mut energy = 0.0;
            for chunk in items.chunks(CHUNK) {
                local.e = 0.0;
                for it in chunk {
                    row(it, &mut local, col_of);
                }
                energy += local.e;
            }
            let first = local.rows.col.len() - local.g.len();
            for (&c, &v) in local.rows.col[first..].iter().zip(&local.g) {
                self.g[c as usize] += v;
            }
            self.rows = std::mem::take(&mut local.rows);
            self.scratch = local;
            return energy;
        }
        let make = |chunk: &[T]| {
            let mut local = Local {
                rows: JacobianRows {
                    ptr: vec![0],
                    col: Vec::with_capacity(8 * chunk.len()),
                    d: Vec::with_capacity(8 * chunk.len()),
                },
                ..Local::default()
            };
            for it in chunk {
                row(it, &mut local, col_of);
            }
            local
        };
        let locals: Vec<Local> = items.par_chunks(CHUNK).map(make).collect();
        let (blocks, entries) = locals
            .iter()
            .fold((0, 0), |(b, e), l| (b + l.rows.ptr.len() - 1, e + l.rows.col.len()));
        self.rows.ptr.reserve(blocks);
        self.rows.col.reserve(entries);
        self.rows.d.reserve(entries);
        let mut energy = 0.0;
        for local in locals {
            energy += local.e;
            self.rows.append(&local.rows);
            for (&c, &v) in local.rows.col.iter().zip(&local.g) {
                self.g[c as usize] += v;
            }
        }
        energy
    }
}

/// Σ f(item) over `items`, in parallel chunks added in order (deterministic).
fn chunked_sum<T: Sync>(items: &[T], f: impl Fn(&T) -> f64 + Sync) -> f64 {
    let sum = |c: &[T]| c.iter().map(&f).sum::<f64>();
    let parts: Vec<f64> = if items.len() <= SEQUENTIAL_ROWS {
        items.chunks(CHUNK).map(sum).collect()
    } else {
        items.par_chunks(CHUNK).map(sum).collect()
    };
    parts.iter().sum()
}

/// One block of the stacked residual: its energy, and its rows assembled into the normal
/// equations. Rows must be pushed in an order and with entries that do not depend on φ.
trait Block: Sync {
    fn term(&self) -> Term;
    fn energy(&self, phi: &[f64]) -> f64;
    /// Pushes the block's rows into `acc`; returns its energy (the same bits as `energy`).
    fn assemble(&self, phi: &[f64], acc: &mut Assembler) -> f64;
}

struct HighlightBlock<'a> {
    term: &'a HighlightTerm<'a>,
    rows: Vec<u32>,
}

impl Block for HighlightBlock<'_> {
    fn term(&self) -> Term {
        Term::Highlight
    }
    fn energy(&self, phi: &[f64]) -> f64 {
        chunked_sum(&self.rows, |&i| {
            let r = self.term.residual(phi, i as usize);
            r[0] * r[0] + r[1] * r[1]
        })
    }
    fn assemble(&self, phi: &[f64], acc: &mut Assembler) -> f64 {
        acc.rows(&self.rows, |&i, local, col_of| {
            let mut entries = std::mem::take(&mut local.entries);
            let r = self.term.jacobian_into(phi, i as usize, &mut entries);
            local.push(col_of, entries.iter().copied(), r);
            local.entries = entries;
        })
    }
}

struct PositionBlock<'a> {
    term: &'a HighlightTerm<'a>,
    rows: Vec<u32>,
}

impl Block for PositionBlock<'_> {
    fn term(&self) -> Term {
        Term::Position
    }
    fn energy(&self, phi: &[f64]) -> f64 {
        chunked_sum(&self.rows, |&i| {
            let r = self.term.position_row(phi, i as usize).0;
            r * r
        })
    }
    fn assemble(&self, phi: &[f64], acc: &mut Assembler) -> f64 {
        acc.rows(&self.rows, |&i, local, col_of| {
            let (r, d) = self.term.position_row(phi, i as usize);
            local.push(col_of, std::iter::once((i, [d, 0.0])), [r, 0.0]);
        })
    }
}

struct SmoothnessBlock {
    edges: Vec<(u32, u32, f64, f64)>, // (i, j, ρ_ij, √(λ_s w_ij)), i < j, at least one free
    k: u32,
}

impl Block for SmoothnessBlock {
    fn term(&self) -> Term {
        Term::Smoothness
    }
    fn energy(&self, phi: &[f64]) -> f64 {
        chunked_sum(&self.edges, |&(i, j, rho, s)| {
            let r = edge_residual_scaled(phi[i as usize], phi[j as usize], rho, s, self.k).0;
            r * r
        })
    }
    fn assemble(&self, phi: &[f64], acc: &mut Assembler) -> f64 {
        acc.rows(&self.edges, |&(i, j, rho, s), local, col_of| {
            let (r, di, dj) =
                edge_residual_scaled(phi[i as usize], phi[j as usize], rho, s, self.k);
            local.push(col_of, [(i, [di, 0.0]), (j, [dj, 0.0])].into_iter(), [r, 0.0]);
        })
    }
}

/// A hinge whose rows the solver assembles alike: per vertex ([`GradientHinge`]) or per face
/// ([`FaceTurningHinge`]).
trait HingeRows: Sync {
    fn kind(&self) -> HingeKind;
    fn residual(&self, phi: &[f64], row: usize) -> f64;
    /// The residual, with its nonzero derivatives pushed into `entries`.
    fn jacobian(&self, phi: &[f64], row: usize, entries: &mut Vec<(u32, f64)>) -> f64;
}

impl HingeRows for GradientHinge<'_> {
    fn kind(&self) -> HingeKind {
        self.kind
    }
    fn residual(&self, phi: &[f64], row: usize) -> f64 {
        GradientHinge::residual(self, phi, row)
    }
    fn jacobian(&self, phi: &[f64], row: usize, entries: &mut Vec<(u32, f64)>) -> f64 {
        GradientHinge::jacobian(self, phi, row, entries)
    }
}

impl HingeRows for FaceTurningHinge<'_> {
    fn kind(&self) -> HingeKind {
        self.kind
    }
    fn residual(&self, phi: &[f64], row: usize) -> f64 {
        FaceTurningHinge::residual(self, phi, row)
    }
    fn jacobian(&self, phi: &[f64], row: usize, entries: &mut Vec<(u32, f64)>) -> f64 {
        FaceTurningHinge::jacobian(self, phi, row, entries)
    }
}

struct HingeBlock<H> {
    hinge: H,
    rows: Vec<u32>,
}

impl<H: HingeRows> Block for HingeBlock<H> {
    fn term(&self) -> Term {
        match self.hinge.kind() {
            HingeKind::Turning => Term::Turning,
            HingeKind::Splay => Term::Splay,
        }
    }
    fn energy(&self, phi: &[f64]) -> f64 {
        chunked_sum(&self.rows, |&i| {
            let r = self.hinge.residual(phi, i as usize);
            r * r
        })
    }
    fn assemble(&self, phi: &[f64], acc: &mut Assembler) -> f64 {
        acc.rows(&self.rows, |&i, local, col_of| {
            let mut entries = std::mem::take(&mut local.entries1);
            let r = self.hinge.jacobian(phi, i as usize, &mut entries);
            local.push(col_of, entries.iter().map(|&(v, d)| (v, [d, 0.0])), [r, 0.0]);
            local.entries1 = entries;
        })
    }
}

struct LockBlock {
    locks: Vec<(u32, f64, f64)>, // (vertex, angle, √(λ A))
    k: u32,
}

impl Block for LockBlock {
    fn term(&self) -> Term {
        Term::Locks
    }
    fn energy(&self, phi: &[f64]) -> f64 {
        chunked_sum(&self.locks, |&(i, a, s)| {
            let r = lock_residual(phi[i as usize], a, s, self.k).0;
            r * r
        })
    }
    fn assemble(&self, phi: &[f64], acc: &mut Assembler) -> f64 {
        acc.rows(&self.locks, |&(i, a, s), local, col_of| {
            let (r, d) = lock_residual(phi[i as usize], a, s, self.k);
            local.push(col_of, std::iter::once((i, [d, 0.0])), [r, 0.0]);
        })
    }
}

pub(super) struct System<'a> {
    pub(super) col_of: &'a [Option<u32>],
    pub(super) free: &'a [u32],
    blocks: Vec<Box<dyn Block + 'a>>,
}

impl System<'_> {
    pub(super) fn energy(&self, phi: &[f64]) -> Energies {
        let mut e = Energies::default();
        for b in &self.blocks {
            e.add(b.term(), b.energy(phi));
        }
        e
    }

    /// Assembles the Jacobian's row blocks and Jᵀr at `phi` into `acc` (reset first). The
    /// blocks come in an order and with columns that depend only on the mesh and the free set,
    /// so their structure is the same at every iteration.
    ///
    /// Returns the energies at `phi` (the same bits as [`System::energy`]: the same residuals
    /// summed in the same chunks).
    pub(super) fn assemble(&self, phi: &[f64], acc: &mut Assembler) -> Energies {
        acc.reset();
        let mut e = Energies::default();
        for b in &self.blocks {
            e.add(b.term(), b.assemble(phi, acc));
        }
        e
    }
}

/// The free set of a solve and what its blocks take from it: each free vertex's column, the
/// vertices whose gradient stencil holds a free angle, and the edges with a free end. Made once
/// for the solves of one free set (the optimizer's starts, probes and continuation stages);
/// with the stencil's users ([`crate::geometry::GradientStencil::users`]) it visits only
/// the free vertices and their neighbours, and holds the same lists as the scan of the part.
pub struct Region {
    col_of: Vec<Option<u32>>,
    free: Vec<u32>,
    touched: Vec<u32>,
    /// (i, j, slot) of the edges i < j with a free end and a positive cotangent weight, in
    /// the order of i, then of i's slots.
    edges: Vec<(u32, u32, u32)>,
}

impl Region {
    /// The region of the `free` vertices (out-of-range ones dropped) of `g`, with the
    /// cotangent weights `w` (one per adjacency slot) and, when lent, the stencil's users.
    pub fn new(g: &Geometry, free: &[u32], w: &[f64], users: Option<&StencilUsers>) -> Region {
        let nv = g.num_vertices();
        let mut col_of = vec![None; nv];
        let mut free_sorted: Vec<u32> =
            free.iter().copied().filter(|&v| (v as usize) < nv).collect();
        free_sorted.sort_unstable();
        free_sorted.dedup();
        for (c, &v) in free_sorted.iter().enumerate() {
            col_of[v as usize] = Some(c as u32);
        }
        // Vertices whose Eq. 10 stencil touches a free angle (itself or a neighbour).
        let touched: Vec<u32> = match users {
            Some(u) if u.num_vertices() == nv => {
                let mut t = free_sorted.clone();
                for &j in &free_sorted {
                    t.extend_from_slice(u.of(j as usize));
                }
                t.sort_unstable();
                t.dedup();
                t
            }
            _ => (0..nv as u32)
                .filter(|&i| {
                    col_of[i as usize].is_some()
                        || g.stencil
                            .range(i as usize)
                            .any(|e| col_of[g.stencil.neighbor[e] as usize].is_some())
                })
                .collect(),
        };
        // An edge with a free end starts at a free vertex or at a neighbour of one (the
        // adjacency is symmetric): those, in ascending order, as the scan of the part meets them.
        let mut near = free_sorted.clone();
        for &v in &free_sorted {
            near.extend_from_slice(g.adjacency.neighbors(v as usize));
        }
        near.sort_unstable();
        near.dedup();
        let mut edges = Vec::new();
        if w.len() == g.adjacency.num_slots() {
            for &i in &near {
                let i = i as usize;
                for s in g.adjacency.slots(i) {
                    let j = g.adjacency.target(s);
                    if i < j && (col_of[i].is_some() || col_of[j].is_some()) && w[s] > 0.0 {
                        edges.push((i as u32, j as u32, s as u32));
                    }
                }
            }
        }
        Region { col_of, free: free_sorted, touched, edges }
    }

    /// The free vertices, ascending.
    pub fn free(&self) -> &[u32] {
        &self.free
    }
}

/// The stacked system of [`super::solve_cached`] over the free vertices of `region`: their
/// columns, and a block per term that has rows touching them (`w`: the cotangent weights the
/// region was made with).
pub(super) fn build_system<'a>(
    mesh: &Mesh,
    term: &'a HighlightTerm,
    region: &'a Region,
    options: &LmOptions,
    w: &[f64],
) -> System<'a> {
    let g = term.geometry;
    let nv = g.num_vertices();
    let col_of = &region.col_of[..];
    let k = term.symmetry.k();
    let mut blocks: Vec<Box<dyn Block + 'a>> = Vec::new();
    let rows =
        region.touched.iter().copied().filter(|&i| term.target_q[i as usize].is_some()).collect();
    blocks.push(Box::new(HighlightBlock { term, rows }));
    // A position row depends on its own angle only: the free vertices with a target.
    let rows: Vec<u32> =
        region.free.iter().copied().filter(|&i| term.target_g[i as usize].is_some()).collect();
    if !rows.is_empty() {
        blocks.push(Box::new(PositionBlock { term, rows }));
    }
    if options.smoothness > 0.0 {
        let edges = region
            .edges
            .iter()
            .map(|&(i, j, s)| {
                let s = s as usize;
                (i, j, g.transport[s], edge_scale(options.smoothness * w[s]))
            })
            .collect();
        blocks.push(Box::new(SmoothnessBlock { edges, k }));
    }
    blocks.extend(hinge_blocks(mesh, term, options, col_of, &region.touched));
    let locks: Vec<(u32, f64, f64)> = options
        .soft_locks
        .iter()
        .filter(|l| (l.0 as usize) < nv && col_of[l.0 as usize].is_some() && l.2 > 0.0)
        .map(|&(v, a, wl)| (v, a, (wl * g.areas[v as usize]).max(0.0).sqrt()))
        .collect();
    if !locks.is_empty() {
        blocks.push(Box::new(LockBlock { locks, k }));
    }
    System { col_of, free: &region.free, blocks }
}

/// The blocks of the vertex hinges (turning, splay: rows at the `touched` vertices) and of
/// the face hinges (turning, splay: the faces with a free corner) that `options` switch on.
fn hinge_blocks<'a>(
    mesh: &Mesh,
    term: &'a HighlightTerm,
    options: &LmOptions,
    col_of: &[Option<u32>],
    touched: &[u32],
) -> Vec<Box<dyn Block + 'a>> {
    let g = term.geometry;
    let mut blocks: Vec<Box<dyn Block + 'a>> = Vec::new();
    for (opt, kind) in [(options.turning, HingeKind::Turning), (options.splay, HingeKind::Splay)] {
        if let Some(h) = opt {
            if h.weight > 0.0 && h.bound > 0.0 && h.bound.is_finite() {
                let hinge = GradientHinge {
                    geometry: g,
                    symmetry: term.symmetry,
                    form: term.form,
                    kind,
                    bound: h.bound,
                    weight: h.weight,
                };
                blocks.push(Box::new(HingeBlock { hinge, rows: touched.to_vec() }));
            }
        }
    }
    for (opt, kind) in
        [(options.turning_faces, HingeKind::Turning), (options.splay_faces, HingeKind::Splay)]
    {
        if let Some(h) = opt {
            if h.weight > 0.0 && h.bound > 0.0 && h.bound.is_finite() {
                let faces: Vec<_> = FaceTurningHinge::frames(mesh)
                    .into_iter()
                    .filter(|f| f.corners.iter().any(|&v| col_of[v as usize].is_some()))
                    .collect();
                let hinge = FaceTurningHinge {
                    geometry: g,
                    symmetry: term.symmetry,
                    faces,
                    kind,
                    radius: 1.0 / h.bound,
                    weight: h.weight,
                };
                let rows = (0..hinge.rows() as u32).collect();
                blocks.push(Box::new(HingeBlock { hinge, rows }));
            }
        }
    }
    blocks
}
