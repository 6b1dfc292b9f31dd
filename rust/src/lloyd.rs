//! Lloyd iterations with exact pruning (the engine behind [`crate::kmeans`]).
//!
//! Each row keeps an upper bound `u` on the distance to its centre and lower bounds on the
//! distance to the other centres, *anchored* at the iteration `t` where they were last
//! computed: at iteration `now` they are loosened by the net displacement of the centres since
//! `t` (`‖c(now) - c(t)‖`, Newling & Fleuret's "ns" bounds), not by the sum of every step's
//! displacement. A row is left alone when `u < max(l, s_a)` (`s_a`: half the distance from its
//! centre to the nearest other centre, Hamerly's test). With few centres (`k ≤ 32`) a row that
//! fails is compared with every centre at once; where the CPU has AVX-512 each row also keeps
//! one lower bound per centre (Elkan's bounds, f32 rounded down), tested before that
//! comparison (with AVX2 only, reading these bounds costs more than the distances they save:
//! 30-40 % slower on 32k × 30 segment projections and 100k × 30 blobs, k = 10 and 30). With
//! more centres a failing row gets its `u`
//! recomputed and, if still needed, is compared only with the centres lying within `2u` of its
//! own centre (the others are provably farther). Every pruning decision keeps a safety margin
//! of `1e-11 ×` the data diameter, so the labels equal those of brute-force Lloyd except for
//! rows whose two nearest centres are tied within that margin.
//!
//! The M-step updates per-cluster sums incrementally with the rows whose label changed
//! (compensated with TwoSum, so their error stays at the level of a freshly computed sum), in a
//! fixed order: results do not depend on the number of threads.

use rayon::prelude::*;

use crate::sqdist::{sq_dist, sq_dists, two_nearest, Panel};

/// Rows per parallel task of the bound tests.
const CHUNK: usize = 2048;
/// Rows per distance-kernel call.
const GROUP: usize = 64;
/// Number of past iterations a bound may stay anchored to before it is re-anchored.
const WINDOW: usize = 24;
/// Memory allowed for the per-chunk partial sums of the first M-step.
const PARTIAL_BYTES: usize = 128 << 20;
/// Up to this many centres, rows that fail the bound tests are compared with every centre
/// (cheap); above, only with the centres near their own (restricted scan).
const DIRECT_MAX_K: usize = 32;
/// Largest number of per-centre lower bounds kept (f32, 4 bytes each).
const ELKAN_MAX_BOUNDS: usize = 32 << 20;
/// Pruning margin, relative to the data diameter.
const MARGIN: f64 = 1e-11;

/// Result of one Lloyd run.
pub(crate) struct LloydRun {
    pub centers: Vec<f64>,
    pub labels: Vec<u32>,
    pub inertia: f64,
    pub n_iter: usize,
}

/// Run Lloyd from `init` (row-major `k × d`); `tol_abs` is the absolute tolerance on the total
/// squared centre shift, `diameter` bounds the distances (for the pruning margin). `scan`
/// forces how rows failing the bound tests are handled; `None` chooses by `k` and the CPU.
#[allow(clippy::too_many_arguments)]
pub(crate) fn lloyd(
    x: &[f64],
    n: usize,
    d: usize,
    init: &[f64],
    k: usize,
    max_iter: usize,
    tol_abs: f64,
    diameter: f64,
    scan: Option<Scan>,
) -> LloydRun {
    let scan = scan.unwrap_or_else(|| Scan::default_for(k));
    let (direct, elkan) = match scan {
        Scan::Restricted => (false, false),
        Scan::Direct => (true, false),
        Scan::DirectElkan => (true, true),
    };
    let mut st = State::new(x, n, d, k, init, MARGIN * diameter, direct, elkan);
    let mut strict = false;
    let mut n_iter = 0;
    for it in 0..max_iter {
        n_iter = it + 1;
        let changes = st.e_step();
        let shift = st.m_step(&changes);
        if it > 0 && changes.is_empty() {
            strict = true;
            break;
        }
        if shift <= tol_abs {
            break;
        }
    }
    if !strict {
        st.e_step();
    }
    let inertia = st.inertia();
    LloydRun {
        centers: st.centers,
        labels: st.labels,
        inertia,
        n_iter,
    }
}

/// How the rows that fail the bound tests are handled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scan {
    /// Tighten `u`, then compare with the centres near the row's own (many centres).
    Restricted,
    /// Compare with every centre (few centres).
    Direct,
    /// As `Direct`, after a test of per-centre (Elkan) lower bounds.
    DirectElkan,
}

impl Scan {
    /// `Restricted` above `DIRECT_MAX_K` centres; below, `DirectElkan` where AVX-512 makes the
    /// per-centre bounds cheap to test, `Direct` elsewhere (see the module docs).
    fn default_for(k: usize) -> Self {
        if k > DIRECT_MAX_K {
            Scan::Restricted
        } else if crate::simd::active() == crate::simd::Level::Avx512 {
            Scan::DirectElkan
        } else {
            Scan::Direct
        }
    }
}

/// A label change `(row, old, new)`.
type Change = (u32, u32, u32);

struct State<'a> {
    x: &'a [f64],
    n: usize,
    d: usize,
    k: usize,
    slack: f64,
    /// Compare failing rows with every centre (few centres) instead of the restricted scan.
    direct: bool,
    /// Index of the next E-step (its centres are `centers`).
    now: usize,
    centers: Vec<f64>,
    panel: Panel,
    /// Centres of the last `WINDOW + 1` E-steps, ring-indexed by E-step.
    hist: Vec<Vec<f64>>,
    labels: Vec<u32>,
    upper: Vec<f64>,
    t_upper: Vec<u32>,
    lower: Vec<f64>,
    t_lower: Vec<u32>,
    /// Elkan-style lower bounds on the distance to every centre (direct mode with few centres):
    /// `kl` f32 values per row, rounded down, anchored at `t_lower`. `kl == 1` when unused.
    lowk: Vec<f32>,
    kl: usize,
    /// Per-cluster coordinate sums (with Neumaier compensation) and counts.
    sums: Vec<f64>,
    comp: Vec<f64>,
    counts: Vec<u64>,
    /// The first E-step already produced the sums.
    first_sums_done: bool,
}

impl<'a> State<'a> {
    #[allow(clippy::too_many_arguments)]
    fn new(
        x: &'a [f64],
        n: usize,
        d: usize,
        k: usize,
        init: &[f64],
        slack: f64,
        direct: bool,
        elkan: bool,
    ) -> Self {
        let mut hist = vec![Vec::new(); WINDOW + 1];
        hist[0] = init.to_vec();
        let panel = Panel::from_centers(init, k, d);
        let elkan = elkan && direct && n.saturating_mul(panel.kpad()) <= ELKAN_MAX_BOUNDS;
        let kl = if elkan { panel.kpad() } else { 1 };
        Self {
            x,
            n,
            d,
            k,
            slack,
            direct,
            now: 0,
            centers: init.to_vec(),
            panel,
            hist,
            labels: vec![0; n],
            upper: vec![0.0; n],
            t_upper: vec![0; n],
            lower: vec![0.0; n],
            t_lower: vec![0; n],
            lowk: vec![f32::INFINITY; n * kl],
            kl,
            sums: vec![0.0; k * d],
            comp: vec![0.0; k * d],
            counts: vec![0; k],
            first_sums_done: false,
        }
    }

    fn row(&self, i: usize) -> &'a [f64] {
        &self.x[i * self.d..(i + 1) * self.d]
    }

    /// Assign every row to its nearest centre; returns the label changes in a fixed order.
    fn e_step(&mut self) -> Vec<Change> {
        let changes = if self.now == 0 {
            self.full_scan()
        } else {
            self.pruned_scan()
        };
        self.now += 1;
        changes
    }

    /// First E-step: every row against every centre.
    fn full_scan(&mut self) -> Vec<Change> {
        let (x, d, k, kl, n) = (self.x, self.d, self.k, self.kl, self.n);
        let panel = &self.panel;
        // The first M-step needs the sums of every cluster: gather them per chunk while the
        // rows are in cache, when the per-chunk partials fit in memory.
        let fused = n
            .div_ceil(CHUNK)
            .saturating_mul(k)
            .saturating_mul(d)
            .saturating_mul(8)
            <= PARTIAL_BYTES;
        let parts: Vec<Option<(Vec<f64>, Vec<u64>)>> = self
            .labels
            .par_chunks_mut(CHUNK)
            .zip(self.upper.par_chunks_mut(CHUNK))
            .zip(self.lower.par_chunks_mut(CHUNK))
            .zip(self.lowk.par_chunks_mut(CHUNK * kl))
            .enumerate()
            .map(|(b, (((lab, up), lo), lk))| {
                let kp = panel.kpad();
                let base = b * CHUNK;
                let mut buf = vec![0.0; GROUP * kp];
                for g in 0..lab.len().div_ceil(GROUP) {
                    let (s, e) = (g * GROUP, ((g + 1) * GROUP).min(lab.len()));
                    let rows: Vec<&[f64]> = (base + s..base + e)
                        .map(|i| &x[i * d..(i + 1) * d])
                        .collect();
                    sq_dists(&rows, panel, &mut buf);
                    for r in 0..e - s {
                        let dists = &buf[r * kp..r * kp + k];
                        let (best, bd, sd) = two_nearest(dists);
                        lab[s + r] = best as u32;
                        up[s + r] = bd.sqrt();
                        lo[s + r] = sd.sqrt();
                        if kl > 1 {
                            store_bounds(&mut lk[(s + r) * kl..(s + r) * kl + k], dists);
                        }
                    }
                }
                fused.then(|| partial_sums(x, d, k, base, lab))
            })
            .collect();
        if fused {
            self.set_sums(parts.iter().flatten());
        }
        self.first_sums_done = fused;
        self.t_upper.fill(0);
        self.t_lower.fill(0);
        // Every row gets its first label: report it as a change from "none" (u32::MAX).
        (0..n as u32)
            .map(|i| (i, u32::MAX, self.labels[i as usize]))
            .collect()
    }

    /// Later E-steps: bound tests, then restricted scans of the rows that fail them.
    fn pruned_scan(&mut self) -> Vec<Change> {
        let (d, k, now, slack) = (self.d, self.k, self.now, self.slack);
        // Net displacement of every centre since each anchor still in the window, with the
        // largest and second largest per anchor (for the lower bounds).
        let lo_t = now.saturating_sub(WINDOW - 1);
        let span = now - lo_t;
        // Rows of `ks ≥ k` values (zero padding up to the bound width in Elkan mode).
        let ks = self.kl.max(k);
        let mut disp = vec![0.0; span * ks];
        let mut dmax = vec![(0.0f64, usize::MAX, 0.0f64); span];
        for t in lo_t..now {
            let old = &self.hist[t % (WINDOW + 1)];
            let row = &mut disp[(t - lo_t) * ks..(t - lo_t) * ks + k];
            let (mut m1, mut a1, mut m2) = (0.0f64, usize::MAX, 0.0f64);
            for j in 0..k {
                let p = sq_dist(&self.centers[j * d..(j + 1) * d], &old[j * d..(j + 1) * d]).sqrt();
                row[j] = p;
                if p > m1 {
                    m2 = m1;
                    m1 = p;
                    a1 = j;
                } else if p > m2 {
                    m2 = p;
                }
            }
            dmax[t - lo_t] = (m1, a1, m2);
        }
        let half = self.half_separation();

        // Pass 1 (parallel over fixed chunks): bound tests, tightening of u. Rows that still
        // fail are collected; with few centres they are compared with all of them at once.
        let x = self.x;
        let centers = &self.centers;
        let panel = &self.panel;
        let direct = self.direct;
        let kl = self.kl;
        let elkan = kl > 1;
        type Pass1 = (Vec<u32>, Vec<Change>, Vec<f64>);
        let pass1: Vec<Pass1> = self
            .labels
            .par_chunks_mut(CHUNK)
            .zip(self.upper.par_chunks_mut(CHUNK))
            .zip(self.t_upper.par_chunks_mut(CHUNK))
            .zip(self.lower.par_chunks_mut(CHUNK))
            .zip(self.t_lower.par_chunks_mut(CHUNK))
            .zip(self.lowk.par_chunks_mut(CHUNK * kl))
            .enumerate()
            .map(|(b, (((((lab, up), tu), lo), tl), lk))| {
                let base = b * CHUNK;
                let row = |i: usize| &x[(base + i) * d..(base + i + 1) * d];
                let mut scan = Vec::new();
                // Largest u among the failing rows of each centre (restricted scans).
                let mut umax = if direct { Vec::new() } else { vec![0.0f64; k] };
                for i in 0..lab.len() {
                    let a = lab[i] as usize;
                    let (ta, tb) = (tu[i] as usize, tl[i] as usize);
                    let ub = if ta == now {
                        up[i]
                    } else {
                        up[i] + disp[(ta - lo_t) * ks + a]
                    };
                    let lb = if tb == now {
                        lo[i]
                    } else {
                        let (m1, a1, m2) = dmax[tb - lo_t];
                        lo[i] - if a == a1 { m2 } else { m1 }
                    };
                    let h = half[a];
                    let mut m = if lb > h { lb } else { h };
                    let mut tightened = false;
                    if elkan && ub + slack >= m {
                        // Per-centre bounds: min over j ≠ a of l_j - ‖c_j(now) - c_j(t)‖.
                        let lrow = &lk[i * kl..(i + 1) * kl];
                        let zero = [0.0; 0];
                        let dr = if tb == now {
                            &zero[..]
                        } else {
                            &disp[(tb - lo_t) * ks..(tb - lo_t + 1) * ks]
                        };
                        let lbk = min_except(lrow, a, dr);
                        if lbk > m {
                            m = lbk;
                        }
                    }
                    if ub + slack >= m {
                        if direct {
                            // Few centres: comparing with all of them costs about as much as
                            // reading the row to tighten u, and refreshes every bound.
                            scan.push(i as u32);
                            continue;
                        }
                        let u = sq_dist(row(i), &centers[a * d..(a + 1) * d]).sqrt();
                        up[i] = u;
                        tu[i] = now as u32;
                        if u + slack >= m {
                            scan.push(i as u32);
                            if u > umax[a] {
                                umax[a] = u;
                            }
                            continue;
                        }
                        tightened = true;
                    }
                    // Kept: move anchors about to leave the window to `now`.
                    if span == WINDOW - 1 {
                        if !tightened && ta == lo_t {
                            up[i] = ub;
                            tu[i] = now as u32;
                        }
                        if tb == lo_t {
                            lo[i] = lb;
                            tl[i] = now as u32;
                            if elkan {
                                let dr = &disp[(tb - lo_t) * ks..(tb - lo_t) * ks + k];
                                for (l, &p) in lk[i * kl..i * kl + k].iter_mut().zip(dr) {
                                    *l = round_down(*l as f64 - p);
                                }
                            }
                        }
                    }
                }
                let mut changes = Vec::new();
                if direct && !scan.is_empty() {
                    let kp = panel.kpad();
                    let mut buf = vec![0.0; GROUP.min(scan.len()) * kp];
                    for grp in scan.chunks(GROUP) {
                        let rows: Vec<&[f64]> = grp.iter().map(|&i| row(i as usize)).collect();
                        sq_dists(&rows, panel, &mut buf);
                        for (r, &i) in grp.iter().enumerate() {
                            let i = i as usize;
                            let dists = &buf[r * kp..r * kp + k];
                            let (best, bd, sd) = two_nearest(dists);
                            if elkan {
                                store_bounds(&mut lk[i * kl..i * kl + k], dists);
                            }
                            if best as u32 != lab[i] {
                                changes.push(((base + i) as u32, lab[i], best as u32));
                                lab[i] = best as u32;
                            }
                            up[i] = bd.sqrt();
                            lo[i] = sd.sqrt();
                            tu[i] = now as u32;
                            tl[i] = now as u32;
                        }
                    }
                    scan.clear();
                }
                (scan, changes, umax)
            })
            .collect();
        if direct {
            return pass1.into_iter().flat_map(|(_, c, _)| c).collect();
        }

        // Candidate centres of each centre a: those within 2·max(u) of it (any other centre
        // is farther from every failing row of a than a itself), with their distances, in
        // index order; `next[a]`: distance to the nearest centre left out.
        let mut umax = vec![0.0f64; k];
        for (_, _, um) in &pass1 {
            for (m, &v) in umax.iter_mut().zip(um) {
                if v > *m {
                    *m = v;
                }
            }
        }
        let kp = self.panel.kpad();
        let cands: Vec<(Vec<(u32, f64)>, f64)> = (0..k)
            .into_par_iter()
            .with_min_len(8)
            .map(|a| {
                if umax[a] == 0.0 {
                    return (Vec::new(), f64::INFINITY);
                }
                let radius = 2.0 * umax[a] + 2.0 * slack;
                let mut buf = vec![0.0; kp];
                sq_dists(&[&centers[a * d..(a + 1) * d]], &self.panel, &mut buf);
                let mut list = Vec::new();
                let mut next = f64::INFINITY;
                for (j, &v) in buf[..k].iter().enumerate() {
                    let dist = v.sqrt();
                    if dist <= radius || j == a {
                        list.push((j as u32, if j == a { 0.0 } else { dist }));
                    } else if dist < next {
                        next = dist;
                    }
                }
                (list, next)
            })
            .collect();

        // Pass 2 (parallel over the same chunks): each failing row against the candidates of
        // its centre that lie within 2u of that centre.
        let changes: Vec<Vec<Change>> = self
            .labels
            .par_chunks_mut(CHUNK)
            .zip(self.upper.par_chunks_mut(CHUNK))
            .zip(self.lower.par_chunks_mut(CHUNK))
            .zip(self.t_lower.par_chunks_mut(CHUNK))
            .zip(pass1.par_iter())
            .enumerate()
            .map(|(b, ((((lab, up), lo), tl), (scan, _, _)))| {
                let base = b * CHUNK;
                let mut changes = Vec::new();
                for (s, &i) in scan.iter().enumerate() {
                    if let Some(&ahead) = scan.get(s + 4) {
                        crate::sqdist::prefetch_row(
                            &x[(base + ahead as usize) * d..(base + ahead as usize + 1) * d],
                        );
                    }
                    let i = i as usize;
                    let row = &x[(base + i) * d..(base + i + 1) * d];
                    let a = lab[i] as usize;
                    let u = up[i];
                    let reach = 2.0 * u + 2.0 * slack;
                    let (list, next_a) = &cands[a];
                    let mut next = *next_a;
                    let (mut best, mut bd, mut sd) = (u32::MAX, f64::INFINITY, f64::INFINITY);
                    for &(j, dist) in list {
                        if dist > reach {
                            if dist < next {
                                next = dist;
                            }
                            continue;
                        }
                        let ju = j as usize;
                        let v = sq_dist(row, &centers[ju * d..(ju + 1) * d]);
                        if v < bd {
                            sd = bd;
                            bd = v;
                            best = j;
                        } else if v < sd {
                            sd = v;
                        }
                    }
                    if best != lab[i] {
                        changes.push(((base + i) as u32, lab[i], best));
                        lab[i] = best;
                    }
                    let l = sd.sqrt().min(next - u);
                    up[i] = bd.sqrt();
                    lo[i] = l;
                    tl[i] = now as u32;
                }
                changes
            })
            .collect();
        changes.into_iter().flatten().collect()
    }

    /// `0.5 × min_{j' ≠ j} ‖c_j - c_j'‖` for every centre (`+inf` when k = 1).
    fn half_separation(&self) -> Vec<f64> {
        let (k, d) = (self.k, self.d);
        let kp = self.panel.kpad();
        (0..k)
            .into_par_iter()
            .with_min_len(16)
            .map(|j| {
                let mut buf = vec![0.0; kp];
                sq_dists(&[&self.centers[j * d..(j + 1) * d]], &self.panel, &mut buf);
                let m = buf[..k]
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != j)
                    .fold(f64::INFINITY, |m, (_, &v)| m.min(v));
                0.5 * m.sqrt()
            })
            .collect()
    }

    /// Update the sums with the label changes, move the centres; returns `Σ_j ‖Δc_j‖²`.
    fn m_step(&mut self, changes: &[Change]) -> f64 {
        let (d, k) = (self.d, self.k);
        if self.now == 1 {
            if !self.first_sums_done {
                self.fresh_sums();
            }
        } else {
            for (c, &(i, old, new)) in changes.iter().enumerate() {
                if let Some(&(ahead, _, _)) = changes.get(c + 8) {
                    crate::sqdist::prefetch_row(self.row(ahead as usize));
                }
                let row = self.row(i as usize);
                let (o, nw) = (old as usize, new as usize);
                let (s_o, c_o) = (
                    &mut self.sums[o * d..(o + 1) * d],
                    &mut self.comp[o * d..(o + 1) * d],
                );
                for ((s, c), &v) in s_o.iter_mut().zip(c_o.iter_mut()).zip(row) {
                    two_sum(s, c, -v);
                }
                let (s_n, c_n) = (
                    &mut self.sums[nw * d..(nw + 1) * d],
                    &mut self.comp[nw * d..(nw + 1) * d],
                );
                for ((s, c), &v) in s_n.iter_mut().zip(c_n.iter_mut()).zip(row) {
                    two_sum(s, c, v);
                }
                self.counts[o] -= 1;
                self.counts[nw] += 1;
            }
        }
        // Totals used for this M-step (a copy: re-seeding empty clusters must not leak into
        // the label-consistent running sums).
        let mut totals: Vec<f64> = self
            .sums
            .iter()
            .zip(&self.comp)
            .map(|(s, c)| s + c)
            .collect();
        let mut counts = self.counts.clone();
        if counts.contains(&0) {
            self.relocate_empty(&mut totals, &mut counts);
        }
        let mut shift = 0.0;
        for j in 0..k {
            if counts[j] == 0 {
                continue;
            }
            let alpha = 1.0 / counts[j] as f64;
            let c = &mut self.centers[j * d..(j + 1) * d];
            for t in 0..d {
                let v = totals[j * d + t] * alpha;
                shift += (v - c[t]) * (v - c[t]);
                c[t] = v;
            }
        }
        self.panel.set(&self.centers, k);
        self.hist[self.now % (WINDOW + 1)] = self.centers.clone();
        shift
    }

    /// Sums and counts from scratch (first M-step): per-chunk partials added in chunk order.
    fn fresh_sums(&mut self) {
        let (x, d, k, n) = (self.x, self.d, self.k, self.n);
        let max_chunks = (PARTIAL_BYTES / k.saturating_mul(d).saturating_mul(8).max(1)).max(1);
        let rows = CHUNK.max(n.div_ceil(max_chunks));
        let parts: Vec<(Vec<f64>, Vec<u64>)> = self
            .labels
            .par_chunks(rows)
            .enumerate()
            .map(|(b, lab)| partial_sums(x, d, k, b * rows, lab))
            .collect();
        self.set_sums(parts.iter());
    }

    /// Totals of per-chunk partial sums, added in chunk order.
    fn set_sums<'p>(&mut self, parts: impl Iterator<Item = &'p (Vec<f64>, Vec<u64>)>) {
        self.sums.fill(0.0);
        self.comp.fill(0.0);
        self.counts.fill(0);
        for (s, c) in parts {
            self.sums.iter_mut().zip(s).for_each(|(a, v)| *a += v);
            self.counts.iter_mut().zip(c).for_each(|(a, v)| *a += v);
        }
    }

    /// Re-seed empty clusters with the rows farthest from their own centre.
    fn relocate_empty(&self, sums: &mut [f64], counts: &mut [u64]) {
        let (x, d, n) = (self.x, self.d, self.n);
        let dist: Vec<f64> = (0..n)
            .into_par_iter()
            .with_min_len(1024)
            .map(|i| {
                let a = self.labels[i] as usize;
                sq_dist(&x[i * d..(i + 1) * d], &self.centers[a * d..(a + 1) * d])
            })
            .collect();
        if dist.iter().all(|&v| v == 0.0) {
            return;
        }
        let empty: Vec<usize> = (0..self.k).filter(|&j| counts[j] == 0).collect();
        let mut order: Vec<usize> = (0..n).collect();
        let cmp = |a: &usize, b: &usize| dist[*b].total_cmp(&dist[*a]).then(a.cmp(b));
        let m = empty.len().min(n);
        if m < n {
            order.select_nth_unstable_by(m, cmp);
        }
        order.truncate(m);
        order.sort_by(cmp);
        for (&j, &far) in empty.iter().zip(&order) {
            let old = self.labels[far] as usize;
            let row = &x[far * d..(far + 1) * d];
            for t in 0..d {
                sums[old * d + t] -= row[t];
                sums[j * d + t] = row[t];
            }
            counts[old] -= 1;
            counts[j] = 1;
        }
    }

    fn inertia(&self) -> f64 {
        let (x, d) = (self.x, self.d);
        let parts: Vec<f64> = self
            .labels
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(b, lab)| {
                let mut s = 0.0;
                for (i, &l) in lab.iter().enumerate() {
                    let r = b * CHUNK + i;
                    let l = l as usize;
                    for t in 0..d {
                        let diff = x[r * d + t] - self.centers[l * d + t];
                        s += diff * diff;
                    }
                }
                s
            })
            .collect();
        parts.iter().sum()
    }
}

/// Coordinate sums and counts per cluster of the rows `base..base + labels.len()`.
fn partial_sums(
    x: &[f64],
    d: usize,
    k: usize,
    base: usize,
    labels: &[u32],
) -> (Vec<f64>, Vec<u64>) {
    let mut s = vec![0.0; k * d];
    let mut c = vec![0u64; k];
    for (i, &l) in labels.iter().enumerate() {
        let l = l as usize;
        let r = &x[(base + i) * d..(base + i + 1) * d];
        s[l * d..(l + 1) * d]
            .iter_mut()
            .zip(r)
            .for_each(|(a, v)| *a += v);
        c[l] += 1;
    }
    (s, c)
}

/// `x` as an f32 that is never above it (a lower bound stays a lower bound): moving `x` down
/// by 2⁻²² of its magnitude first outweighs the 2⁻²⁴ relative rounding of the conversion.
/// Branch-free, so loops over it vectorize.
#[inline]
fn round_down(x: f64) -> f32 {
    (x - x.abs() * (1.0 / 4_194_304.0)) as f32
}

/// Per-centre lower bounds from squared distances.
#[inline]
fn store_bounds(dst: &mut [f32], sq: &[f64]) {
    for (l, &v) in dst.iter_mut().zip(sq) {
        *l = round_down(v.sqrt());
    }
}

/// `min_{j ≠ skip} (bounds[j] - disp[j])` (`disp` empty means zero displacement, else as
/// long as `bounds`).
#[inline]
fn min_except(bounds: &[f32], skip: usize, disp: &[f64]) -> f64 {
    assert!(disp.is_empty() || disp.len() == bounds.len());
    #[cfg(target_arch = "x86_64")]
    if crate::simd::active() == crate::simd::Level::Avx512 && bounds.len().is_multiple_of(8) {
        // SAFETY: AVX-512F detected; lengths checked above.
        return unsafe { min_except512(bounds, skip, disp) };
    }
    let mut m = f64::INFINITY;
    for (j, &l) in bounds.iter().enumerate() {
        let v = l as f64 - disp.get(j).copied().unwrap_or(0.0);
        if j != skip && v < m {
            m = v;
        }
    }
    m
}

/// [`min_except`] with AVX-512 (8 bounds per step).
///
/// # Safety
/// AVX-512F available; `bounds.len()` a multiple of 8; `disp` empty or as long as `bounds`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn min_except512(bounds: &[f32], skip: usize, disp: &[f64]) -> f64 {
    use std::arch::x86_64::*;
    let mut m = _mm512_set1_pd(f64::INFINITY);
    let mut j = 0;
    while j < bounds.len() {
        let mut v = _mm512_cvtps_pd(_mm256_loadu_ps(bounds.as_ptr().add(j)));
        if !disp.is_empty() {
            v = _mm512_sub_pd(v, _mm512_loadu_pd(disp.as_ptr().add(j)));
        }
        let keep: __mmask8 = if skip >= j && skip < j + 8 {
            !(1u8 << (skip - j))
        } else {
            0xff
        };
        m = _mm512_mask_min_pd(m, keep, m, v);
        j += 8;
    }
    _mm512_reduce_min_pd(m)
}

/// `s + c += y`, keeping the rounding error of `s + y` in `c` (Knuth's branch-free TwoSum).
#[inline(always)]
fn two_sum(s: &mut f64, c: &mut f64, y: f64) {
    let t = *s + y;
    let bp = t - *s;
    *c += (*s - (t - bp)) + (y - bp);
    *s = t;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_down_never_rounds_up() {
        let mut x = 1.0e-30f64;
        while x < 1.0e30 {
            for v in [x, -x, x * 1.000_000_1, -x * 0.999_999_9] {
                assert!((round_down(v) as f64) <= v, "{v}");
                assert!((round_down(v) as f64) >= v - v.abs() * 1e-6);
            }
            x *= 1.37;
        }
        assert_eq!(round_down(0.0), 0.0);
    }

    #[test]
    fn min_except_skips_one_lane() {
        let bounds: Vec<f32> = (0..16).map(|j| 10.0 + j as f32).collect();
        let disp: Vec<f64> = (0..16).map(|j| if j == 5 { 9.0 } else { 0.5 }).collect();
        // Without the skip the minimum is lane 5 (15 - 9 = 6).
        assert_eq!(min_except(&bounds, 3, &disp), 6.0);
        assert_eq!(min_except(&bounds, 5, &disp), 9.5);
        assert_eq!(min_except(&bounds, 0, &[]), 11.0);
        assert_eq!(min_except(&bounds[..8], 7, &[]), 10.0);
    }

    #[test]
    fn two_sum_keeps_what_plain_addition_loses() {
        let (mut s, mut c) = (1.0e16, 0.0);
        for _ in 0..1000 {
            two_sum(&mut s, &mut c, 1.0);
        }
        for _ in 0..1000 {
            two_sum(&mut s, &mut c, -1.0);
        }
        assert_eq!(s + c, 1.0e16);
        let (mut s, mut c) = (1.0e16, 0.0);
        for _ in 0..1000 {
            two_sum(&mut s, &mut c, 1.0);
        }
        assert_eq!(s + c, 1.0e16 + 1000.0);
    }
}
