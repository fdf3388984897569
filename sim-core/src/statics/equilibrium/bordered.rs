//! A chain's Newton system with a few extra unknowns, solved in `O(n k + k^3)`:
//!
//! ```text
//! [ S  P ] [x]   [a]        S = diag(d) + [a_max(i,j)]  (n x n, the chain's joints)
//! [ Q  R ] [w] = [b]        P: n x k,  Q: k x n,  R: k x k  (k small: contacts, ...)
//! ```
//!
//! `S` has the shape of [`super::structured`] (the springs and every point force on the
//! chain: a force at a point of link `L` adds `F . (X - p_(m-1))` to `a_m` for `m <= L`), so
//! it factors in `O(n)`. Some joints may be **held**: their `x` is given (a joint on its
//! limit in a semismooth Newton step), their rows dropped. The rest is a Schur complement on
//! the `k` extra unknowns (contact forces, rank-one corrections, hair angles):
//! `y0 = S^-1 a`, `Y = S^-1 P` (`k + 1` solves of `O(n)`), then
//! `(R - Q Y) w = b - Q y0` (dense, `k x k`) and `x = y0 - Y w`.
//!
//! **Certified.** The answer is checked against the system itself (its residual, `O(n k)`);
//! one step of iterative refinement follows when the residual is above the tolerance, and if
//! it is still above (an indefinite `S` with a tiny pivot: elimination without pivoting is
//! then unstable), or a pivot vanishes, the whole system is solved densely by LU with partial
//! pivoting ([`SolveStats::dense`] says so). Nothing is allocated once the buffers have grown
//! to the largest system seen.

// Joints, border unknowns and their rows are indexed together: index loops say what they do.
#![allow(clippy::needless_range_loop)]

use nalgebra::DMatrix;

use super::structured::{factor_masked, solve_masked};

/// How a bordered system was solved.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SolveStats {
    /// Whether the structured solve was refined once.
    pub refined: bool,
    /// Whether the dense fallback was used.
    pub dense: bool,
    /// The relative residual of the chain's rows (the structured elimination's accuracy).
    pub relative_residual: f64,
    /// Whether the dense part was rank deficient (redundant constraints: two stuck contacts
    /// at the ends of one rigid link) and was solved in the least-squares sense, with the
    /// least-norm answer along its null space.
    pub truncated: bool,
    /// The residual of the extra unknowns' rows relative to their largest right-hand side:
    /// tiny unless the system is rank deficient and inconsistent (constraints that cannot
    /// all hold: then the least-squares answer leaves it).
    pub border_residual: f64,
}

/// The system and its scratch space (see the module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct BorderedSystem {
    n: usize,
    k: usize,
    /// `d`, `n` entries.
    pub diagonal: Vec<f64>,
    /// `a`, `n` entries.
    pub coefficients: Vec<f64>,
    /// `Some(x_i)` for a held joint.
    pub held: Vec<Option<f64>>,
    /// Column `c` of `P` is `p[c * n .. (c + 1) * n]`.
    pub p: Vec<f64>,
    /// Row `r` of `Q` is `q[r * n .. (r + 1) * n]`.
    pub q: Vec<f64>,
    /// `R`, `k x k`, row-major: `r[i * k + j]`.
    pub r: Vec<f64>,
    /// `a`, `n` entries.
    pub rhs_x: Vec<f64>,
    /// `b`, `k` entries.
    pub rhs_w: Vec<f64>,
    // Scratch.
    /// Per column of `P`, one past its last nonzero entry (0: the column is zero).
    p_len: Vec<usize>,
    /// Per row of `Q`, one past its last nonzero entry (0: the row is zero).
    q_len: Vec<usize>,
    free: Vec<bool>,
    pivots: Vec<f64>,
    coupling: Vec<f64>,
    y: Vec<f64>,
    y0: Vec<f64>,
    work: Vec<f64>,
    schur: DMatrix<f64>,
    schur_rhs: Vec<f64>,
    res_x: Vec<f64>,
    res_w: Vec<f64>,
    truncated: bool,
    border_residual: f64,
}

/// A pivot this small relative to its row's entries means the elimination cannot be trusted.
const PIVOT_FLOOR: f64 = 1e-13;

/// The relative residual accepted from the structured solve.
const RESIDUAL_TOLERANCE: f64 = 1e-11;

impl BorderedSystem {
    /// Clears the system to `n` joints and `k` extra unknowns (all free, everything zero).
    pub fn reset(&mut self, n: usize, k: usize) {
        self.n = n;
        self.k = k;
        reset(&mut self.diagonal, n);
        reset(&mut self.coefficients, n);
        self.held.clear();
        self.held.resize(n, None);
        reset(&mut self.p, n * k);
        reset(&mut self.q, n * k);
        reset(&mut self.r, k * k);
        reset(&mut self.rhs_x, n);
        reset(&mut self.rhs_w, k);
    }

    /// Column `c` of `P`.
    pub fn p_col(&mut self, c: usize) -> &mut [f64] {
        let n = self.n;
        &mut self.p[c * n..(c + 1) * n]
    }

    /// Row `r` of `Q`.
    pub fn q_row(&mut self, r: usize) -> &mut [f64] {
        let n = self.n;
        &mut self.q[r * n..(r + 1) * n]
    }

    /// Entry `(i, j)` of `R`.
    pub fn r_at(&mut self, i: usize, j: usize) -> &mut f64 {
        let k = self.k;
        &mut self.r[i * k + j]
    }

    /// Solves the system into `x` (`n`) and `w` (`k`); `None` if it is singular.
    pub fn solve(&mut self, x: &mut [f64], w: &mut [f64]) -> Option<SolveStats> {
        let mut stats = SolveStats::default();
        self.truncated = false;
        self.measure_supports();
        if self.structured(x, w) {
            stats.relative_residual = self.relative_residual(x, w);
            if stats.relative_residual.is_finite() && stats.relative_residual > RESIDUAL_TOLERANCE {
                // One step of refinement with the same factorization.
                let (mut dx, mut dw) = (vec![0.0; self.n], vec![0.0; self.k]);
                std::mem::swap(&mut self.rhs_x, &mut self.res_x);
                std::mem::swap(&mut self.rhs_w, &mut self.res_w);
                let ok = self.structured_solve_with_factor(&mut dx, &mut dw, true);
                std::mem::swap(&mut self.rhs_x, &mut self.res_x);
                std::mem::swap(&mut self.rhs_w, &mut self.res_w);
                if ok {
                    for (xi, d) in x.iter_mut().zip(&dx) {
                        *xi -= d;
                    }
                    for (wi, d) in w.iter_mut().zip(&dw) {
                        *wi -= d;
                    }
                    stats.refined = true;
                    stats.relative_residual = self.relative_residual(x, w);
                }
            }
            if stats.relative_residual.is_finite()
                && stats.relative_residual <= RESIDUAL_TOLERANCE.sqrt()
            {
                stats.truncated = self.truncated;
                stats.border_residual = self.border_residual;
                return Some(stats);
            }
        }
        stats.dense = true;
        if !self.dense(x, w) {
            return None;
        }
        stats.relative_residual = self.relative_residual(x, w);
        stats.truncated = self.truncated;
        stats.border_residual = self.border_residual;
        stats.relative_residual.is_finite().then_some(stats)
    }

    /// Where the columns of `P` and the rows of `Q` end ([`Self::p_len`], [`Self::q_len`]).
    /// A point force on link `L` touches only the joints `m <= L`, and the angle of a hair
    /// not in contact (most of a long antenna's hairs) none: the products below skip the
    /// zeros (the same sums, term for term; on a 150-link antenna with distal hairs sweeping
    /// a digitized line, 40 of some 45 border unknowns on average were such hair angles).
    fn measure_supports(&mut self) {
        let (n, k) = (self.n, self.k);
        let end = |v: &[f64]| v.iter().rposition(|e| *e != 0.0).map_or(0, |i| i + 1);
        self.p_len.clear();
        self.p_len
            .extend((0..k).map(|c| end(&self.p[c * n..(c + 1) * n])));
        self.q_len.clear();
        self.q_len
            .extend((0..k).map(|r| end(&self.q[r * n..(r + 1) * n])));
    }

    /// The structured solve (factorization included); false when a pivot vanishes or the
    /// Schur complement is singular.
    fn structured(&mut self, x: &mut [f64], w: &mut [f64]) -> bool {
        let n = self.n;
        self.free.clear();
        self.free.extend(self.held.iter().map(Option::is_none));
        reset(&mut self.pivots, n);
        reset(&mut self.coupling, n);
        factor_masked(
            &self.diagonal,
            &self.coefficients,
            &self.free,
            None,
            0.0,
            &mut self.pivots,
            &mut self.coupling,
        );
        // Pivot sizes against the entries they come from and the matrix's own scale.
        let global = (0..n).fold(0.0_f64, |a, m| {
            a.max(self.diagonal[m].abs() + self.coefficients[m].abs())
        });
        let mut shift = 0.0_f64;
        for m in (0..n).rev() {
            if !self.free[m] {
                continue;
            }
            let e = self.coefficients[m] - shift;
            let scale = (self.diagonal[m].abs() + e.abs() + self.coefficients[m].abs()).max(global);
            let p = self.pivots[m];
            if p.abs().partial_cmp(&(PIVOT_FLOOR * scale)) != Some(std::cmp::Ordering::Greater) {
                return false;
            }
            shift += e * self.coupling[m];
        }
        self.structured_solve_with_factor(x, w, false)
    }

    /// The structured solve with the factorization in place; for a `correction` (iterative
    /// refinement) the held joints' values are zero.
    fn structured_solve_with_factor(
        &mut self,
        x: &mut [f64],
        w: &mut [f64],
        correction: bool,
    ) -> bool {
        let (n, k) = (self.n, self.k);
        // Held joints: x given, their effect moved to the right-hand sides.
        reset(&mut self.work, n);
        let mut any_held = false;
        if !correction {
            for (i, h) in self.held.iter().enumerate() {
                if let Some(v) = h {
                    self.work[i] = *v;
                    any_held = true;
                }
            }
        }
        reset(&mut self.y0, n);
        self.y0.copy_from_slice(&self.rhs_x);
        reset(&mut self.schur_rhs, k);
        self.schur_rhs.copy_from_slice(&self.rhs_w);
        if any_held {
            let sx = semiseparable_mul(&self.diagonal, &self.coefficients, &self.work);
            for i in 0..n {
                self.y0[i] -= sx[i];
            }
            for r in 0..k {
                let row = &self.q[r * n..(r + 1) * n];
                let mut sum = 0.0;
                for (i, h) in self.held.iter().enumerate() {
                    if let Some(v) = h {
                        sum += row[i] * v;
                    }
                }
                self.schur_rhs[r] -= sum;
            }
        }
        solve_masked(&self.pivots, &self.coupling, &self.free, &mut self.y0);
        // Y = S^-1 P, column by column.
        reset(&mut self.y, n * k);
        self.y.copy_from_slice(&self.p);
        for c in 0..k {
            if self.p_len[c] == 0 {
                continue;
            }
            solve_masked(
                &self.pivots,
                &self.coupling,
                &self.free,
                &mut self.y[c * n..(c + 1) * n],
            );
        }
        // M = R - Q Y on the free joints, rhs = b - Q y0.
        if self.schur.nrows() != k || self.schur.ncols() != k {
            self.schur = DMatrix::zeros(k, k);
        }
        for i in 0..k {
            let len = self.q_len[i];
            let row = &self.q[i * n..i * n + len];
            let mut rhs = self.schur_rhs[i];
            for j in 0..len {
                if self.free[j] {
                    rhs -= row[j] * self.y0[j];
                }
            }
            self.schur_rhs[i] = rhs;
            for c in 0..k {
                if len == 0 || self.p_len[c] == 0 {
                    self.schur[(i, c)] = self.r[i * k + c];
                    continue;
                }
                let col = &self.y[c * n..c * n + len];
                let mut sum = 0.0;
                for j in 0..len {
                    sum += row[j] * col[j];
                }
                self.schur[(i, c)] = self.r[i * k + c] - sum;
            }
        }
        if k > 0 {
            let Some(truncated) = solve_small(&mut self.schur, &mut self.schur_rhs, w) else {
                return false;
            };
            self.truncated |= truncated;
        }
        for j in 0..n {
            x[j] = match self.held[j] {
                Some(_) if correction => 0.0,
                Some(v) => v,
                None => {
                    let mut v = self.y0[j];
                    for c in 0..k {
                        if self.p_len[c] > 0 {
                            v -= self.y[c * n + j] * w[c];
                        }
                    }
                    v
                }
            };
        }
        x.iter().all(|v| v.is_finite())
    }

    /// The residual of `(x, w)` into `res_x`, `res_w` (free rows only; held rows are exact)
    /// and its size relative to the terms that make it up.
    fn relative_residual(&mut self, x: &[f64], w: &[f64]) -> f64 {
        let (n, k) = (self.n, self.k);
        let sx = semiseparable_mul(&self.diagonal, &self.coefficients, x);
        reset(&mut self.res_x, n);
        reset(&mut self.res_w, k);
        let mut scale = 0.0_f64;
        let mut worst = 0.0_f64;
        for i in 0..n {
            if self.held[i].is_some() {
                continue;
            }
            let mut v = sx[i] - self.rhs_x[i];
            let mut size = sx[i].abs() + self.rhs_x[i].abs();
            for c in 0..k {
                if i < self.p_len[c] {
                    let t = self.p[c * n + i] * w[c];
                    v += t;
                    size += t.abs();
                }
            }
            self.res_x[i] = v;
            scale = scale.max(size);
            worst = worst.max(v.abs() / size.max(f64::MIN_POSITIVE));
            if !v.is_finite() {
                return f64::INFINITY;
            }
        }
        // The extra unknowns' rows are the dense solve's (least squares where it is rank
        // deficient): their residual is measured apart ([`SolveStats::border_residual`]).
        let rhs_scale = self.rhs_w.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        let mut border = 0.0_f64;
        for r in 0..k {
            let row = &self.q[r * n..r * n + self.q_len[r]];
            let mut v = -self.rhs_w[r];
            for (q, xj) in row.iter().zip(x) {
                v += q * xj;
            }
            for c in 0..k {
                v += self.r[r * k + c] * w[c];
            }
            self.res_w[r] = v;
            border = border.max(v.abs());
        }
        self.border_residual = if rhs_scale > 0.0 {
            border / rhs_scale
        } else if border > 0.0 {
            f64::INFINITY
        } else {
            0.0
        };
        let _ = scale;
        worst
    }

    /// The whole system densely, by LU with partial pivoting.
    fn dense(&mut self, x: &mut [f64], w: &mut [f64]) -> bool {
        let (n, k) = (self.n, self.k);
        let dim = n + k;
        let mut m = DMatrix::<f64>::zeros(dim, dim);
        let mut rhs = nalgebra::DVector::<f64>::zeros(dim);
        for i in 0..n {
            if let Some(v) = self.held[i] {
                m[(i, i)] = 1.0;
                rhs[i] = v;
                continue;
            }
            for j in 0..n {
                m[(i, j)] = self.coefficients[i.max(j)];
            }
            m[(i, i)] += self.diagonal[i];
            for c in 0..k {
                m[(i, n + c)] = self.p[c * n + i];
            }
            rhs[i] = self.rhs_x[i];
        }
        for r in 0..k {
            for j in 0..n {
                m[(n + r, j)] = self.q[r * n + j];
            }
            for c in 0..k {
                m[(n + r, n + c)] = self.r[r * k + c];
            }
            rhs[n + r] = self.rhs_w[r];
        }
        let mut rhs: Vec<f64> = rhs.iter().copied().collect();
        let mut sol = vec![0.0; dim];
        let Some(truncated) = solve_small(&mut m, &mut rhs, &mut sol) else {
            return false;
        };
        self.truncated |= truncated;
        x.copy_from_slice(&sol[..n]);
        w.copy_from_slice(&sol[n..]);
        true
    }
}

/// Solves the small dense system `m w = rhs` (both overwritten: rows and columns
/// equilibrated) into `out`: LU with partial pivoting, or, where `m` is (numerically) rank
/// deficient, the least-squares answer of least norm (an SVD truncated at a relative
/// [`RANK_TOLERANCE`]). Returns whether it was truncated; `None` if nothing finite came out.
fn solve_small(m: &mut DMatrix<f64>, rhs: &mut [f64], out: &mut [f64]) -> Option<bool> {
    let k = rhs.len();
    for i in 0..k {
        let scale = m.row(i).amax();
        if scale > 0.0 && scale.is_finite() {
            for c in 0..k {
                m[(i, c)] /= scale;
            }
            rhs[i] /= scale;
        }
    }
    let mut col_scale = vec![1.0; k];
    for (c, cs) in col_scale.iter_mut().enumerate() {
        let scale = m.column(c).amax();
        if scale > 0.0 && scale.is_finite() {
            for i in 0..k {
                m[(i, c)] /= scale;
            }
            *cs = scale;
        }
    }
    let b = nalgebra::DVector::from_column_slice(rhs);
    let lu = m.clone().lu();
    let u = lu.u();
    let (mut lo, mut hi) = (f64::INFINITY, 0.0_f64);
    for i in 0..k {
        let v = u[(i, i)].abs();
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let (sol, truncated) = if lo > RANK_TOLERANCE * hi && lo.is_finite() {
        (lu.solve(&b)?, false)
    } else {
        let svd = m.clone().svd(true, true);
        let top = svd.singular_values.iter().copied().fold(0.0_f64, f64::max);
        if top.is_nan() || top <= 0.0 {
            return None;
        }
        (svd.solve(&b, RANK_TOLERANCE * top).ok()?, true)
    };
    for c in 0..k {
        out[c] = sol[c] / col_scale[c];
    }
    out.iter().all(|v| v.is_finite()).then_some(truncated)
}

/// Singular values below this, relative to the largest, count as zero in [`solve_small`].
const RANK_TOLERANCE: f64 = 1e-12;

/// `(diag(d) + [a_max(i,j)]) v` in `O(n)`.
fn semiseparable_mul(d: &[f64], a: &[f64], v: &[f64]) -> Vec<f64> {
    let n = d.len();
    let mut out = vec![0.0; n];
    let mut prefix = 0.0;
    for i in 0..n {
        prefix += v[i];
        out[i] = d[i] * v[i] + a[i] * prefix;
    }
    let mut suffix = 0.0;
    for i in (0..n).rev() {
        out[i] += suffix;
        suffix += a[i] * v[i];
    }
    out
}

fn reset(v: &mut Vec<f64>, len: usize) {
    v.clear();
    v.resize(len, 0.0);
}

#[cfg(test)]
mod tests {
    //! The structured solve against a dense LU of the same system, with held joints.
    #![allow(clippy::unwrap_used)]

    use super::*;

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((*state >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    }

    /// Fills the chain's part of `sys` at random: diagonal, coefficients, right-hand side,
    /// and joint `i` held where `i % every == at` (`held = (every, at)`).
    fn random_chain(sys: &mut BorderedSystem, seed: &mut u64, held: (usize, usize)) {
        for i in 0..sys.n {
            sys.diagonal[i] = 1.0 + lcg(seed).abs();
            sys.coefficients[i] = 0.3 * lcg(seed);
            sys.rhs_x[i] = lcg(seed);
            if i % held.0 == held.1 {
                sys.held[i] = Some(lcg(seed));
            }
        }
    }

    /// Solves `sys` by the structured solve (which must not fall back to the dense one),
    /// asserts that it agrees with the dense LU, and returns its `x`.
    fn structured_matching_dense(sys: &mut BorderedSystem) -> Vec<f64> {
        let (n, k) = (sys.n, sys.k);
        let (mut x, mut w) = (vec![0.0; n], vec![0.0; k]);
        let stats = sys.solve(&mut x, &mut w).unwrap();
        assert!(!stats.dense, "n = {n}: {stats:?}");
        let (mut xd, mut wd) = (vec![0.0; n], vec![0.0; k]);
        assert!(sys.dense(&mut xd, &mut wd));
        for (a, b) in x.iter().zip(&xd).chain(w.iter().zip(&wd)) {
            assert!(
                (a - b).abs() <= 1e-9 * (1.0 + b.abs()),
                "n = {n}: {a} vs {b}"
            );
        }
        x
    }

    #[test]
    fn structured_solve_matches_dense_with_held_joints_and_borders() {
        let mut seed = 7u64;
        for (n, k) in [(1, 0), (3, 2), (9, 4), (40, 7), (150, 12)] {
            let mut sys = BorderedSystem::default();
            sys.reset(n, k);
            random_chain(&mut sys, &mut seed, (5, 3));
            for c in 0..k {
                for i in 0..n {
                    sys.p_col(c)[i] = lcg(&mut seed);
                    sys.q_row(c)[i] = lcg(&mut seed);
                }
                for j in 0..k {
                    *sys.r_at(c, j) = lcg(&mut seed) + if c == j { 2.0 } else { 0.0 };
                }
                sys.rhs_w[c] = lcg(&mut seed);
            }
            let x = structured_matching_dense(&mut sys);
            for i in 0..n {
                if let Some(v) = sys.held[i] {
                    assert_eq!(x[i], v);
                }
            }
        }
    }

    /// Borders shaped like a contact step's: a point force on link `L` fills its column and
    /// row up to `L` only, and a hair angle not in contact (most of them, on a long antenna
    /// with hairs) none of them, its row of `R` its diagonal alone. The solve that skips
    /// those zeros ([`BorderedSystem::measure_supports`]) agrees with the dense LU.
    #[test]
    fn structured_solve_with_truncated_and_empty_borders_matches_dense() {
        let mut seed = 11u64;
        for (n, k) in [(4, 3), (36, 9), (150, 45)] {
            let mut sys = BorderedSystem::default();
            sys.reset(n, k);
            random_chain(&mut sys, &mut seed, (7, 5));
            for c in 0..k {
                let empty = c % 4 != 0;
                // Where the border's column and row end (a link of the chain), or nothing.
                let len = if empty {
                    0
                } else {
                    1 + ((lcg(&mut seed) + 0.5) * (n - 1) as f64) as usize
                };
                for i in 0..len {
                    sys.p_col(c)[i] = lcg(&mut seed);
                    sys.q_row(c)[i] = lcg(&mut seed);
                }
                for j in 0..k {
                    *sys.r_at(c, j) = if c == j {
                        2.0 + lcg(&mut seed)
                    } else if empty || j % 4 != 0 {
                        0.0
                    } else {
                        lcg(&mut seed)
                    };
                }
                sys.rhs_w[c] = lcg(&mut seed);
            }
            structured_matching_dense(&mut sys);
            assert!(sys.p_len.iter().filter(|&&l| l == 0).count() >= k / 2);
        }
    }

    #[test]
    fn a_vanishing_pivot_falls_back_to_the_dense_solve() {
        // S = [[1 + a1, a1], [a1, 0 + a1]] with a = (0, 0): the tip pivot is 0, yet the
        // bordered system is regular.
        let mut sys = BorderedSystem::default();
        sys.reset(2, 1);
        sys.diagonal.copy_from_slice(&[1.0, 0.0]);
        sys.p_col(0).copy_from_slice(&[0.0, 1.0]);
        sys.q_row(0).copy_from_slice(&[0.0, 1.0]);
        sys.rhs_x.copy_from_slice(&[1.0, 2.0]);
        sys.rhs_w[0] = 3.0;
        let (mut x, mut w) = (vec![0.0; 2], vec![0.0; 1]);
        let stats = sys.solve(&mut x, &mut w).unwrap();
        assert!(stats.dense);
        assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 3.0).abs() < 1e-14);
        assert!((w[0] - 2.0).abs() < 1e-14);
    }
}
