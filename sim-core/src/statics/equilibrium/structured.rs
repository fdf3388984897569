//! The `O(n)` linear algebra of the chain: matrices `H = diag(d) + A` with
//! `A_ij = a_max(i,j)`, the shape of the Hessian of a tip load
//! (`a_m = f . (p_n - p_(m-1))`, [`crate::statics::energy::Potential`]).
//!
//! # Elimination along the chain
//! Eliminating the most distal unknown `m` of such a matrix leaves a Schur complement of the
//! same shape: every entry `a_max(i,j)` with `i, j < m` loses the same amount
//! `e_m^2 / p_m`. So a single shift `s` carries everything, and from the tip inwards:
//!
//! ```text
//! s = 0;  for m = n, n-1, ..., 1:  e_m = a_m - s,  p_m = d_m + e_m,  c_m = e_m / p_m,
//!                                  s += e_m c_m
//! ```
//!
//! gives `H = U diag(p) U^T` with `U` unit upper triangular and `U_jm = c_m` for every
//! `j < m` (one number per column). Solving is two sweeps with running sums:
//! `z_j = b_j - sum_{m > j} c_m z_m` (tip to base), then
//! `x_m = z_m / p_m - c_m sum_{j < m} x_j` (base to tip). Both the factorization and a
//! solve cost `O(n)` and allocate nothing.
//!
//! By Sylvester's law of inertia the signs of the pivots `p_m` are the signs of the
//! eigenvalues of `H`: the number of negative pivots is the number of negative eigenvalues.
//! This is how the solver detects an indefinite Newton matrix and how
//! [`stability`](super::stability) counts inertia. When asked to, the factorization
//! replaces a pivot `p_m < delta` by `max(|p_m|, delta)`: an exact factorization of
//! `H + E`, `E` diagonal and non-negative, which is positive definite (in the spirit of Gill and
//! Murray's modified Cholesky; the solver itself prefers a Levenberg shift `H + sigma I`, see
//! [`super::newton`], and keeps this as its last resort).
//!
//! A subset of the unknowns (the joints not held on a limit) keeps the shape: the same sweeps
//! skip the held entries.
//!
//! Without pivoting the elimination is backward stable when `H` is positive definite (it is
//! Gaussian elimination on an SPD matrix, in reverse order); for indefinite `H` the pivots
//! are used only to count inertia or are modified as above.

use nalgebra::DMatrix;

/// The inertia found by a factorization.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Inertia {
    /// Pivots `< 0` before any modification.
    pub negative: usize,
    /// Pivots with `|p| <= zero_tolerance` before any modification.
    pub near_zero: usize,
    /// Whether some pivot was modified.
    pub modified: bool,
}

/// Factorizes `diag(d) + [a_max(i,j)]` restricted to the entries with `free[m]`, into
/// `pivots` and `coupling` (entries of held joints are left untouched). With
/// `modify = Some(delta)`, pivots below `delta` become `max(|p|, delta)`.
pub(crate) fn factor_masked(
    d: &[f64],
    a: &[f64],
    free: &[bool],
    modify: Option<f64>,
    zero_tolerance: f64,
    pivots: &mut [f64],
    coupling: &mut [f64],
) -> Inertia {
    let mut inertia = Inertia::default();
    let mut s = 0.0_f64;
    for m in (0..d.len()).rev() {
        if !free[m] {
            continue;
        }
        let e = a[m] - s;
        let mut p = d[m] + e;
        if p.abs() <= zero_tolerance {
            inertia.near_zero += 1;
        }
        if p < 0.0 {
            inertia.negative += 1;
        }
        match modify {
            Some(delta) if p < delta => {
                p = p.abs().max(delta);
                inertia.modified = true;
            }
            _ => {}
        }
        if p == 0.0 {
            p = f64::MIN_POSITIVE;
        }
        pivots[m] = p;
        let c = e / p;
        coupling[m] = c;
        s += e * c;
    }
    inertia
}

/// Solves with a factorization from [`factor_masked`], in place: `b` becomes `x` on the
/// free entries and 0 on the held ones.
pub(crate) fn solve_masked(pivots: &[f64], coupling: &[f64], free: &[bool], b: &mut [f64]) {
    let mut t = 0.0_f64;
    for j in (0..b.len()).rev() {
        if !free[j] {
            b[j] = 0.0;
            continue;
        }
        let z = b[j] - t;
        t += coupling[j] * z;
        b[j] = z / pivots[j];
    }
    let mut sum = 0.0_f64;
    for m in 0..b.len() {
        if !free[m] {
            continue;
        }
        let x = b[m] - coupling[m] * sum;
        b[m] = x;
        sum += x;
    }
}

/// A symmetric matrix `H_ij = d_i delta_ij + a_max(i,j)` (`n x n`, 0-based), stored in `O(n)`.
#[derive(Clone, Debug, PartialEq)]
pub struct SemiseparableMatrix {
    /// The diagonal part `d`.
    pub diagonal: Vec<f64>,
    /// The coefficients `a`: entry `(i, j)` of the structured part is `a[max(i, j)]`.
    pub coefficients: Vec<f64>,
}

/// The `U diag(p) U^T` factorization of a [`SemiseparableMatrix`].
#[derive(Clone, Debug, PartialEq)]
pub struct SemiseparableFactor {
    pivots: Vec<f64>,
    coupling: Vec<f64>,
    inertia: Inertia,
}

impl SemiseparableMatrix {
    /// A matrix from its diagonal and coefficients (equal lengths).
    ///
    /// # Panics
    /// Never; mismatched lengths are truncated to the shorter one.
    pub fn new(diagonal: Vec<f64>, coefficients: Vec<f64>) -> SemiseparableMatrix {
        let n = diagonal.len().min(coefficients.len());
        let (mut diagonal, mut coefficients) = (diagonal, coefficients);
        diagonal.truncate(n);
        coefficients.truncate(n);
        SemiseparableMatrix {
            diagonal,
            coefficients,
        }
    }

    /// The dimension.
    pub fn dim(&self) -> usize {
        self.diagonal.len()
    }

    /// `H x` in `O(n)`: `(H x)_i = d_i x_i + a_i sum_{j <= i} x_j + sum_{j > i} a_j x_j`.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        let n = self.dim();
        let mut out = vec![0.0; n];
        let mut prefix = 0.0;
        for i in 0..n {
            prefix += x[i];
            out[i] = self.diagonal[i] * x[i] + self.coefficients[i] * prefix;
        }
        let mut suffix = 0.0;
        for i in (0..n).rev() {
            out[i] += suffix;
            suffix += self.coefficients[i] * x[i];
        }
        out
    }

    /// The dense matrix (`O(n^2)`), for references.
    pub fn to_dense(&self) -> DMatrix<f64> {
        let n = self.dim();
        DMatrix::from_fn(n, n, |i, j| {
            self.coefficients[i.max(j)] + if i == j { self.diagonal[i] } else { 0.0 }
        })
    }

    /// Factorizes in `O(n)` without modification.
    pub fn factor(&self) -> SemiseparableFactor {
        self.factor_impl(None)
    }

    /// Factorizes `H + E` in `O(n)`, `E >= 0` diagonal, with every pivot at least `delta`
    /// (the last-resort modified Newton matrix of the solver).
    pub fn factor_modified(&self, delta: f64) -> SemiseparableFactor {
        self.factor_impl(Some(delta))
    }

    fn factor_impl(&self, modify: Option<f64>) -> SemiseparableFactor {
        let n = self.dim();
        let mut pivots = vec![0.0; n];
        let mut coupling = vec![0.0; n];
        let free = vec![true; n];
        let inertia = factor_masked(
            &self.diagonal,
            &self.coefficients,
            &free,
            modify,
            0.0,
            &mut pivots,
            &mut coupling,
        );
        SemiseparableFactor {
            pivots,
            coupling,
            inertia,
        }
    }
}

impl SemiseparableFactor {
    /// The inertia counted from the pivots.
    pub fn inertia(&self) -> Inertia {
        self.inertia
    }

    /// The pivots `p_m` (their signs are the inertia).
    pub fn pivots(&self) -> &[f64] {
        &self.pivots
    }

    /// Solves `H x = b` in `O(n)` (entries beyond the dimension are ignored).
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let n = self.pivots.len();
        let mut x: Vec<f64> = b.iter().take(n).copied().collect();
        x.resize(n, 0.0);
        let free = vec![true; n];
        solve_masked(&self.pivots, &self.coupling, &free, &mut x);
        x
    }
}
