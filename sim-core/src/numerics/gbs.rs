//! The Gragg-Bulirsch-Stoer extrapolation step (Hairer, Norsett & Wanner, *Solving Ordinary
//! Differential Equations I*, II.9): the modified midpoint rule with step counts
//! 2, 4, ..., 2K (`K` = [`GBS_COLUMNS`]) and Aitken-Neville extrapolation in `h^2`, of order
//! `2K`, with the difference of the last two diagonal entries as the error estimate. The
//! step-size control is the caller's (the elastica's shooting integrator).

/// Number of columns of the extrapolation tableau (step counts 2, 4, ..., 2K).
pub(crate) const GBS_COLUMNS: usize = 6;

/// One Gragg-Bulirsch-Stoer step of size `h` from `(s, y)` for `y' = rhs(s, y)`: returns the
/// extrapolated state and the scaled error estimate, the largest over the first `M` components
/// of `|T_KK - T_K,K-1| / (scale[c] + rtol max(|y[c]|, |T_KK[c]|))`. `scale` holds the absolute
/// tolerances of the components the error is controlled on (the first `M`; the rest, such as
/// variational components, ride along), `rtol` the relative one. An error of `rhs` is returned
/// as it is.
pub(crate) fn gbs_step<const N: usize, const M: usize, E>(
    rhs: impl Fn(f64, &[f64; N]) -> Result<[f64; N], E>,
    s: f64,
    h: f64,
    y: &[f64; N],
    scale: &[f64; M],
    rtol: f64,
) -> Result<([f64; N], f64), E> {
    let f0 = rhs(s, y)?;
    let mut table = [[0.0f64; N]; GBS_COLUMNS];
    let mut counts = [0usize; GBS_COLUMNS];
    let mut last_two = ([0.0f64; N], [0.0f64; N]);
    for j in 0..GBS_COLUMNS {
        let n = 2 * (j + 1);
        counts[j] = n;
        let hs = h / n as f64;
        // Modified midpoint rule with n substeps.
        let mut z_prev = *y;
        let mut z = add_scaled(y, &f0, hs);
        for m in 1..n {
            let f = rhs(s + m as f64 * hs, &z)?;
            let z_next = add_scaled(&z_prev, &f, 2.0 * hs);
            z_prev = z;
            z = z_next;
        }
        // Aitken-Neville in h^2: row j of the tableau, overwriting in place.
        let mut current = z;
        for k in 1..=j {
            let ratio = (counts[j] as f64 / counts[j - k] as f64).powi(2);
            let previous = table[k - 1];
            table[k - 1] = current;
            let mut next = [0.0; N];
            for c in 0..N {
                next[c] = current[c] + (current[c] - previous[c]) / (ratio - 1.0);
            }
            if j == GBS_COLUMNS - 1 && k == j {
                last_two = (current, next);
            }
            current = next;
        }
        table[j] = current;
    }
    let (lower, best) = last_two;
    let mut err = 0.0f64;
    for c in 0..M {
        let tol = scale[c] + rtol * y[c].abs().max(best[c].abs());
        err = err.max((best[c] - lower[c]).abs() / tol);
    }
    Ok((best, err))
}

/// `a + h b`.
fn add_scaled<const N: usize>(a: &[f64; N], b: &[f64; N], h: f64) -> [f64; N] {
    let mut out = *a;
    for (o, v) in out.iter_mut().zip(b) {
        *o += h * v;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_step_of_a_rotation_matches_the_exact_solution() {
        // y = (cos s, sin s) solves y' = (-y_1, y_0); one step of 0.25 from s = 0.
        let rhs = |_s: f64, y: &[f64; 2]| -> Result<[f64; 2], ()> { Ok([-y[1], y[0]]) };
        let (y, err) = gbs_step(rhs, 0.0, 0.25, &[1.0, 0.0], &[1e-13, 1e-13], 1e-13).unwrap();
        assert!((y[0] - 0.25f64.cos()).abs() < 2e-15, "{}", y[0]);
        assert!((y[1] - 0.25f64.sin()).abs() < 2e-15, "{}", y[1]);
        assert!(err <= 1.0, "{err}");
    }

    #[test]
    fn a_step_too_long_reports_an_error_above_one_and_rhs_errors_pass_through() {
        let rhs = |_s: f64, y: &[f64; 1]| -> Result<[f64; 1], ()> { Ok([10.0 * y[0]]) };
        let (_, err) = gbs_step(rhs, 0.0, 2.0, &[1.0], &[1e-13], 1e-13).unwrap();
        assert!(err > 1.0, "{err}");
        let failing = |s: f64, y: &[f64; 1]| if s > 0.1 { Err(s) } else { Ok([y[0]]) };
        assert!(gbs_step(failing, 0.0, 1.0, &[1.0], &[1e-13], 1e-13).is_err());
    }
}
