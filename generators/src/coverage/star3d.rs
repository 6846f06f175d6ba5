//! Exact star discrepancy in three dimensions for research sizes (n = 10,000 in seconds), by a
//! sweep over the first axis and a blocked plane of upper envelopes, after Dobkin, Eppstein and
//! Mitchell ("Computing the discrepancy with applications to supersampling patterns", ACM
//! Trans. Graph. 15(4), 1996, §4: the sweep turns the `d`-dimensional problem into `n`
//! insertions into a `(d − 1)`-dimensional one, and blocks of the critical grid keep each
//! insertion and each query to `O(n^{3/2})` cells; with `d = 3` the total is `O(n^{5/2})`).
//!
//! The critical grid is `Γ = Γ₀ × Γ₁ × Γ₂`, each `Γ_k` the distinct `k`-th coordinates and 1.
//! At the sweep's level `z ∈ Γ₀`, with `G(i, j)` the number of points whose first coordinate is
//! below `z` (open) or at most `z` (closed) and whose second and third are below the `i`-th and
//! `j`-th grid values (open) or at most them (closed), the local discrepancies are
//! `z·u_i·v_j − G/n` (open boxes) and `G/n − z·u_i·v_j` (closed boxes). For a fixed cell both
//! are lines in `z`: the plane keeps, per block of `B × B` cells, the upper envelope of its
//! cells' lines (a convex-hull trick; the lines' slopes `±u_i·v_j` do not change, so each block
//! sorts them once), a count added to the whole block lazily, and a pointer into the envelope
//! that only moves forward as `z` grows. Inserting a point adds 1 to a quadrant of cells:
//! blocks inside it take the lazy count, the `O(m/B)` blocks it cuts recount their cells and
//! rebuild their envelope when next asked.

use rayon::prelude::*;

/// Largest side of a block of cells (a plane of `m × m` cells takes `m^(1/3)`, at most this).
/// On this project's 2-core machine, the exact star discrepancy of 10,000 Halton points in
/// d = 3 took 45.3 s with 16, 44.0 s with 20, 46.5 s with 24 and 53.0 s with 32 (`cargo run
/// --release -p paracosm-generators --example star3d -- 10000 halton`); 384 points in d = 4
/// (385 planes of up to 385² cells) took 8.8 s with 20 everywhere, 4.1 s with `m^(1/3)`, 4.2 s
/// with `0.7·m^(1/3)` and 4.9 s with `1.4·m^(1/3)` (`... -- 384 halton 4`, beside another job).
const BLOCK: usize = 20;

/// One block of the plane: its cells sorted by `u_i·v_j`, both terms' counts in that order,
/// and each term's envelope.
struct Block {
    /// First row and column of the block in the plane; columns.
    i0: usize,
    j0: usize,
    w: usize,
    /// `n · u_i · v_j` of the cells, ascending (`n` times, so that a count is a line's
    /// intercept as it is).
    slope: Vec<f64>,
    /// Each cell's position in `slope` (row-major `h × w`).
    position: Vec<u16>,
    /// The cell at each position (the inverse of `position`).
    cell: Vec<u16>,
    /// Per term (0 open, 1 closed), the counts by position, without the lazy count.
    counts: [Vec<u32>; 2],
    /// Per term, the envelope: positions whose lines are each the largest on an interval of
    /// `z`, in increasing slope of the term's line.
    hull: [Vec<u16>; 2],
    /// Per term, the envelope's entry that was largest at the last `z` asked.
    at: [usize; 2],
    /// Per term, the factor of the volume (1 in d = 3; the first coordinate's level when the
    /// plane serves a prefix of a d = 4 set, `star4d.rs`).
    scale: [f64; 2],
}

impl Block {
    /// The term's line at position `k`, as (slope, intercept) in units of `1/n`: open
    /// `n·σ₀·s·z − c`, closed `c − n·σ₁·s·z` (`σ` the term's [`Block::scale`]).
    fn line(&self, term: usize, k: usize) -> (f64, f64) {
        let (a, c) = (
            self.slope[k] * self.scale[term],
            f64::from(self.counts[term][k]),
        );
        if term == 0 {
            (a, -c)
        } else {
            (-a, c)
        }
    }

    /// Rebuilds the term's envelope (the lazy count shifts every line alike and is left out)
    /// and resets its pointer.
    fn rebuild(&mut self, term: usize) {
        let len = self.slope.len();
        let mut hull = std::mem::take(&mut self.hull[term]);
        hull.clear();
        for step in 0..len {
            // Lines in increasing slope: the open term's in the sorted order, the closed
            // term's (slope −n·s) in the reverse.
            let k = if term == 0 { step } else { len - 1 - step };
            let (a3, b3) = self.line(term, k);
            if let Some(&last) = hull.last() {
                let (a2, b2) = self.line(term, last as usize);
                if a2 == a3 {
                    if b2 >= b3 {
                        continue;
                    }
                    hull.pop();
                }
            }
            while hull.len() >= 2 {
                let (a1, b1) = self.line(term, hull[hull.len() - 2] as usize);
                let (a2, b2) = self.line(term, hull[hull.len() - 1] as usize);
                // The middle line is nowhere the largest when the outer two cross before it
                // takes over: (b1 − b3)/(a3 − a1) <= (b1 − b2)/(a2 − a1).
                if (b1 - b3) * (a2 - a1) <= (b1 - b2) * (a3 - a1) {
                    hull.pop();
                } else {
                    break;
                }
            }
            hull.push(k as u16);
        }
        self.hull[term] = hull;
        self.at[term] = 0;
    }

    /// The term's current envelope line and the next one, `[a, b, a_next, b_next]`; without
    /// a next line, one that is never larger (`0·z − ∞`).
    fn front(&self, term: usize) -> [f64; 4] {
        let hull = &self.hull[term];
        let at = self.at[term];
        let (a, b) = self.line(term, hull[at] as usize);
        let (an, bn) = match hull.get(at + 1) {
            Some(&k) => self.line(term, k as usize),
            None => (0.0, f64::NEG_INFINITY),
        };
        [a, b, an, bn]
    }
}

/// The plane of cells `(i, j)`, both terms, in blocks.
struct Plane {
    /// Side of a block of cells, at most [`BLOCK`].
    side: usize,
    /// Blocks per row of blocks, and rows of blocks.
    nbj: usize,
    nbi: usize,
    blocks: Vec<Block>,
    /// Per term, the lazy count of each block.
    lazy: [Vec<u32>; 2],
    /// Per term, each block's [`Block::front`], kept beside the others so that a query
    /// reads one dense array and touches a block only when its envelope moves on.
    front: [Vec<[f64; 4]>; 2],
    /// Per term, the blocks whose counts changed since their envelope was built.
    dirty: [Vec<bool>; 2],
}

impl Plane {
    /// The plane over the grid `u × v`, `n` the divisor of the counts (the size of the whole
    /// set) and `scale` each term's factor of the volume.
    fn new(u: &[f64], v: &[f64], n: f64, scale: [f64; 2]) -> Self {
        let (m1, m2) = (u.len(), v.len());
        // An insertion rebuilds O(m / B) blocks of B² cells and a query reads (m / B)² blocks:
        // the two balance at B ≈ m^(1/3), which is BLOCK (tuned at 10,000 points) for the
        // largest planes.
        let side = ((m1.max(m2) as f64).cbrt().round() as usize).clamp(4, BLOCK);
        let (nbi, nbj) = (m1.div_ceil(side), m2.div_ceil(side));
        let blocks = (0..nbi * nbj)
            .into_par_iter()
            .map(|b| {
                let (i0, j0) = ((b / nbj) * side, (b % nbj) * side);
                let (h, w) = (side.min(m1 - i0), side.min(m2 - j0));
                let s = |c: usize| n * (u[i0 + c / w] * v[j0 + c % w]);
                let mut cell: Vec<u16> = (0..(h * w) as u16).collect();
                cell.sort_by(|&a, &b| s(a as usize).total_cmp(&s(b as usize)));
                let mut position = vec![0u16; h * w];
                for (k, &c) in cell.iter().enumerate() {
                    position[c as usize] = k as u16;
                }
                Block {
                    i0,
                    j0,
                    w,
                    slope: cell.iter().map(|&c| s(c as usize)).collect(),
                    position,
                    cell,
                    counts: [vec![0; h * w], vec![0; h * w]],
                    hull: [Vec::new(), Vec::new()],
                    at: [0, 0],
                    scale,
                }
            })
            .collect();
        Plane {
            side,
            nbj,
            nbi,
            blocks,
            lazy: [vec![0; nbi * nbj], vec![0; nbi * nbj]],
            front: [vec![[0.0; 4]; nbi * nbj], vec![[0.0; 4]; nbi * nbj]],
            dirty: [vec![true; nbi * nbj], vec![true; nbi * nbj]],
        }
    }

    /// Adds 1 to the term's count of every cell `(i, j)` with `i >= i0` and `j >= j0`.
    fn add_quadrant(&mut self, term: usize, i0: usize, j0: usize) {
        let (nbi, nbj) = (self.nbi, self.nbj);
        let side = self.side;
        let (bi, bj) = (i0 / side, j0 / side);
        // Blocks whose first row and column are inside take the lazy count; the rest of the
        // quadrant lies in the row of blocks `bi` and the column of blocks `bj`.
        let (fi, fj) = (i0.div_ceil(side), j0.div_ceil(side));
        for r in fi..nbi {
            for l in &mut self.lazy[term][r * nbj + fj..(r + 1) * nbj] {
                *l += 1;
            }
        }
        let row = (bi < fi).then(|| (bj..nbj).map(move |c| bi * nbj + c));
        let column = (bj < fj).then(|| {
            (bi..nbi)
                .filter(move |&r| r != bi || bi == fi)
                .map(move |r| r * nbj + bj)
        });
        for b in row
            .into_iter()
            .flatten()
            .chain(column.into_iter().flatten())
        {
            let blk = &mut self.blocks[b];
            let h = blk.slope.len() / blk.w;
            let (r0, c0) = (i0.saturating_sub(blk.i0), j0.saturating_sub(blk.j0));
            if r0 >= h || c0 >= blk.w {
                continue;
            }
            for r in r0..h {
                for c in c0..blk.w {
                    let k = blk.position[r * blk.w + c] as usize;
                    blk.counts[term][k] += 1;
                }
            }
            self.dirty[term][b] = true;
        }
    }

    /// The term's largest local discrepancy over the cells at `z` (not below the previous `z`
    /// asked of the term), its row and its column. Ties go to the first block in row-major
    /// order, whatever the thread count.
    fn max_at(&mut self, term: usize, z: f64, n: f64) -> (f64, usize, usize) {
        let sign = if term == 0 { -1.0 } else { 1.0 };
        let (value, b) = self
            .blocks
            .par_iter_mut()
            .zip(self.front[term].par_iter_mut())
            .zip(self.dirty[term].par_iter_mut())
            .zip(self.lazy[term].par_iter())
            .enumerate()
            .map(|(b, (((blk, f), dirty), &lazy))| {
                if *dirty {
                    blk.rebuild(term);
                    *f = blk.front(term);
                    *dirty = false;
                }
                while f[2] * z + f[3] >= f[0] * z + f[1] {
                    blk.at[term] += 1;
                    *f = blk.front(term);
                }
                ((f[0] * z + f[1] + sign * f64::from(lazy)) / n, b)
            })
            .reduce(
                || (f64::NEG_INFINITY, usize::MAX),
                |a, b| {
                    if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) {
                        b
                    } else {
                        a
                    }
                },
            );
        let blk = &self.blocks[b];
        let cell = blk.cell[blk.hull[term][blk.at[term]] as usize] as usize;
        (value, blk.i0 + cell / blk.w, blk.j0 + cell % blk.w)
    }
}

/// The exact star discrepancy of `points` (`n × 3`, row-major, in `[0, 1]`, `n < 2^32`) and
/// its witness corner: `max over Γ of max(vol − open count/n, closed count/n − vol)`, the same
/// quantity as the enumeration of the critical grid, in `O(n^{5/2})` time and `O(n²)` memory
/// (about 1.6 GB at n = 10,000).
pub(super) fn exact_3d_sweep(points: &[f64], progress: super::Progress<'_>) -> (f64, Vec<f64>) {
    let n = points.len() / 3;
    let (value, witness, _) = scaled_3d_sweep(points, [1.0, 1.0], n as f64, progress);
    (value, witness)
}

/// The largest of `σ₀·vol − open count/n` and `closed count/n − σ₁·vol` over the critical grid
/// of `points` (`m × 3`, row-major, in `[0, 1]`; `m` may be 0), with `σ = scale` and `n`
/// (any positive divisor, usually the size of a larger set that `points` is part of): its
/// value, the grid corner where it is reached and the term (0 open, 1 closed). With `σ = 1`
/// and `n = m`, the star discrepancy of `points`. `progress` hears of each plane swept.
pub(super) fn scaled_3d_sweep(
    points: &[f64],
    scale: [f64; 2],
    n: f64,
    progress: super::Progress<'_>,
) -> (f64, Vec<f64>, usize) {
    let m = points.len() / 3;
    let grid = |k: usize| {
        let mut g: Vec<f64> = points.chunks_exact(3).map(|p| p[k]).collect();
        g.push(1.0);
        g.sort_by(f64::total_cmp);
        g.dedup();
        g
    };
    let (w, u, v) = (grid(0), grid(1), grid(2));
    let rank = |g: &[f64], x: f64| g.partition_point(|&y| y < x);
    // Points by first coordinate, with their ranks along the other two.
    let mut pts: Vec<(f64, usize, usize)> = points
        .chunks_exact(3)
        .map(|p| (p[0], rank(&u, p[1]), rank(&v, p[2])))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut plane = Plane::new(&u, &v, n, scale);
    let mut best = (f64::NEG_INFINITY, vec![1.0; 3], 0);
    let mut next = 0;
    for (k, &z) in w.iter().enumerate() {
        progress(k as u64, w.len() as u64);
        // Open boxes at z: the points with a first coordinate below z are in.
        let (val, i, j) = plane.max_at(0, z, n);
        if val > best.0 {
            best = (val, vec![z, u[i], v[j]], 0);
        }
        while next < m && pts[next].0 <= z {
            let (_, r1, r2) = pts[next];
            // Open: cell (i, j) counts a point with r1 < i and r2 < j; closed: r1 <= i, r2 <= j.
            plane.add_quadrant(0, r1 + 1, r2 + 1);
            plane.add_quadrant(1, r1, r2);
            next += 1;
        }
        let (val, i, j) = plane.max_at(1, z, n);
        if val > best.0 {
            best = (val, vec![z, u[i], v[j]], 1);
        }
    }
    progress(w.len() as u64, w.len() as u64);
    best
}
