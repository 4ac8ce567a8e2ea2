//! Ordinary least squares for the handful of regressors a calibration needs.
//!
//! Solved by Householder QR on the design matrix rather than by the normal equations, whose
//! condition number is the square of the matrix's: a teach cut at nearly constant feed makes the
//! idle-current column nearly collinear with the intercept, and QR still gets the digits right.

use std::fmt;

/// Why a fit could not be made.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FitError {
    /// Fewer samples than unknowns (after dropping non-finite ones).
    TooFewSamples {
        /// Usable samples.
        samples: usize,
        /// Unknowns.
        unknowns: usize,
    },
    /// The regressors do not vary independently (e.g. a teach cut at one load only).
    RankDeficient {
        /// The regressor that adds nothing to the others.
        column: &'static str,
    },
}

impl fmt::Display for FitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FitError::TooFewSamples { samples, unknowns } => write!(
                f,
                "{samples} usable samples cannot determine {unknowns} coefficients"
            ),
            FitError::RankDeficient { column } => write!(
                f,
                "the samples do not vary in \"{column}\" independently of the other inputs: \
                 calibrate over a range of loads and speeds"
            ),
        }
    }
}

impl std::error::Error for FitError {}

/// A least-squares fit y ≈ X·β with its quality.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// The coefficients β, one per column.
    pub coefficients: Vec<f64>,
    /// Coefficient of determination R² (1 − SS_res / SS_tot); 1 for a perfect fit.
    pub r_squared: f64,
    /// Standard deviation of the residuals, √(SS_res / (n − p)).
    pub residual_std: f64,
    /// Standard error of each coefficient, σ·√((XᵀX)⁻¹)_jj with σ = [`Self::residual_std`]
    /// (0 where n = p: an exact fit says nothing about its spread).
    pub standard_errors: Vec<f64>,
    /// Samples used (rows with any non-finite value are dropped).
    pub samples: usize,
}

/// Fits `y ≈ Σ_j β_j · columns[j]`. Rows where any value is non-finite are skipped.
///
/// ```
/// use cutlab::math::least_squares::fit;
/// let x: Vec<f64> = (0..10).map(f64::from).collect();
/// let y: Vec<f64> = x.iter().map(|x| 2.0 + 0.5 * x).collect();
/// let ones = vec![1.0; 10];
/// let f = fit(&[("intercept", &ones), ("x", &x)], &y).unwrap();
/// assert!((f.coefficients[0] - 2.0).abs() < 1e-12 && (f.coefficients[1] - 0.5).abs() < 1e-12);
/// assert!((f.r_squared - 1.0).abs() < 1e-12);
/// ```
pub fn fit(columns: &[(&'static str, &[f64])], y: &[f64]) -> Result<Fit, FitError> {
    let p = columns.len();
    let rows: Vec<usize> = (0..y.len())
        .filter(|&i| {
            y[i].is_finite()
                && columns
                    .iter()
                    .all(|(_, c)| c.get(i).is_some_and(|v| v.is_finite()))
        })
        .collect();
    let n = rows.len();
    if n < p || p == 0 {
        return Err(FitError::TooFewSamples {
            samples: n,
            unknowns: p,
        });
    }
    // Column-major copies: a[j][k] is column j at usable row k.
    let mut a: Vec<Vec<f64>> = columns
        .iter()
        .map(|(_, c)| rows.iter().map(|&i| c[i]).collect())
        .collect();
    let mut b: Vec<f64> = rows.iter().map(|&i| y[i]).collect();
    let scale: Vec<f64> = a
        .iter()
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .collect();

    // Householder QR, applied to b as we go.
    let mut r = vec![vec![0.0; p]; p];
    for j in 0..p {
        let norm = a[j][j..].iter().map(|v| v * v).sum::<f64>().sqrt();
        // A column whose remaining part is negligible next to its size is a combination of the
        // columns before it.
        if scale[j] == 0.0 || norm <= 1e-10 * scale[j] {
            return Err(FitError::RankDeficient {
                column: columns[j].0,
            });
        }
        let alpha = if a[j][j] > 0.0 { -norm } else { norm };
        let mut v: Vec<f64> = a[j][j..].to_vec();
        v[0] -= alpha;
        let v_norm_sq: f64 = v.iter().map(|x| x * x).sum();
        let reflect = |col: &mut [f64]| {
            let dot: f64 = v.iter().zip(col.iter()).map(|(a, b)| a * b).sum();
            let factor = 2.0 * dot / v_norm_sq;
            for (c, vi) in col.iter_mut().zip(&v) {
                *c -= factor * vi;
            }
        };
        for col in a.iter_mut().skip(j) {
            reflect(&mut col[j..]);
        }
        reflect(&mut b[j..]);
        for (k, col) in a.iter().enumerate().skip(j) {
            r[j][k] = col[j];
        }
    }
    // Back substitution R·β = Qᵀb.
    let mut beta = vec![0.0; p];
    for j in (0..p).rev() {
        let s: f64 = (j + 1..p).map(|k| r[j][k] * beta[k]).sum();
        beta[j] = (b[j] - s) / r[j][j];
    }
    let ss_res: f64 = b[p..].iter().map(|v| v * v).sum();
    let residual_std = if n > p {
        (ss_res / (n - p) as f64).sqrt()
    } else {
        0.0
    };
    // (XᵀX)⁻¹ = R⁻¹·R⁻ᵀ, so the j-th diagonal entry is the squared norm of R⁻¹'s row j. Column
    // e of R⁻¹ solves R·x = e_e by back substitution (upper triangular: x_j = 0 below e).
    let mut row_norms_sq = vec![0.0; p];
    for e in 0..p {
        let mut x = vec![0.0; p];
        for j in (0..=e).rev() {
            let s: f64 = (j + 1..=e).map(|m| r[j][m] * x[m]).sum();
            x[j] = (if j == e { 1.0 } else { 0.0 } - s) / r[j][j];
        }
        for (sum, v) in row_norms_sq.iter_mut().zip(&x) {
            *sum += v * v;
        }
    }
    let standard_errors = row_norms_sq
        .iter()
        .map(|sq| residual_std * sq.sqrt())
        .collect();
    let y_used: Vec<f64> = rows.iter().map(|&i| y[i]).collect();
    let mean = y_used.iter().sum::<f64>() / n as f64;
    let ss_tot: f64 = y_used.iter().map(|v| (v - mean).powi(2)).sum();
    Ok(Fit {
        coefficients: beta,
        r_squared: if ss_tot > 0.0 {
            1.0 - ss_res / ss_tot
        } else {
            1.0
        },
        residual_std,
        standard_errors,
        samples: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn recovers_known_coefficients_with_noise_and_reports_quality() {
        let mut rng = Rng::seed_from(5);
        let n = 2000;
        let load: Vec<f64> = (0..n).map(|_| 1000.0 * rng.uniform()).collect();
        let speed: Vec<f64> = (0..n).map(|_| 500.0 * rng.uniform()).collect();
        let ones = vec![1.0; n];
        let current: Vec<f64> = (0..n)
            .map(|i| 1.5 + 0.002 * speed[i] + 0.01 * load[i] + rng.gaussian(0.05))
            .collect();
        let f = fit(
            &[("idle", &ones), ("speed", &speed), ("load", &load)],
            &current,
        )
        .unwrap();
        assert!((f.coefficients[0] - 1.5).abs() < 0.01);
        assert!((f.coefficients[1] - 0.002).abs() < 2e-5);
        assert!((f.coefficients[2] - 0.01).abs() < 2e-5);
        assert!((f.residual_std - 0.05).abs() < 0.005);
        // Each coefficient's true error is within a few of its standard errors.
        for (got, (truth, se)) in f
            .coefficients
            .iter()
            .zip([1.5, 0.002, 0.01].iter().zip(&f.standard_errors))
        {
            assert!((got - truth).abs() < 4.0 * se, "{got} vs {truth} ± {se}");
        }
        assert!(f.r_squared > 0.99);
    }

    #[test]
    fn agrees_with_the_closed_form_for_a_straight_line() {
        // Slope and intercept from the textbook formulas on exact data with a known residual.
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        let y = [2.1, 3.9, 6.2, 7.8, 10.1];
        let (n, sx, sy) = (5.0, 15.0, 30.1);
        let sxx: f64 = x.iter().map(|v| v * v).sum();
        let sxy: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
        let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
        let intercept = (sy - slope * sx) / n;
        let ones = [1.0; 5];
        let f = fit(&[("intercept", &ones), ("x", &x)], &y).unwrap();
        assert!((f.coefficients[1] - slope).abs() < 1e-12);
        assert!((f.coefficients[0] - intercept).abs() < 1e-12);
    }

    #[test]
    fn non_finite_rows_are_skipped_and_degenerate_data_is_an_error() {
        let ones = [1.0; 4];
        let x = [1.0, 2.0, f64::NAN, 4.0];
        let y = [1.0, 2.0, 3.0, 4.0];
        let f = fit(&[("intercept", &ones), ("x", &x)], &y).unwrap();
        assert_eq!(f.samples, 3);
        let constant = [2.0; 4];
        assert_eq!(
            fit(&[("intercept", &ones), ("load", &constant)], &y),
            Err(FitError::RankDeficient { column: "load" })
        );
        assert_eq!(
            fit(&[("intercept", &ones), ("x", &x)], &y[..1]),
            Err(FitError::TooFewSamples {
                samples: 1,
                unknowns: 2
            })
        );
    }

    #[test]
    fn standard_errors_are_the_closed_form_of_a_straight_line() {
        // y = a + b·x: SE(b) = σ / √Σ(x − x̄)², SE(a) = σ·√(1/n + x̄² / Σ(x − x̄)²).
        let x = [1.0, 2.0, 4.0, 7.0, 11.0, 16.0];
        let y = [2.1, 2.9, 5.2, 7.8, 12.5, 16.4];
        let ones = [1.0; 6];
        let f = fit(&[("intercept", &ones), ("x", &x)], &y).unwrap();
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let sxx: f64 = x.iter().map(|v| (v - mean).powi(2)).sum();
        let se_b = f.residual_std / sxx.sqrt();
        let se_a = f.residual_std * (1.0 / n + mean * mean / sxx).sqrt();
        assert!((f.standard_errors[1] - se_b).abs() < 1e-12 * se_b.max(1.0));
        assert!((f.standard_errors[0] - se_a).abs() < 1e-12 * se_a.max(1.0));
        assert!(f.standard_errors[1] > 0.0);
    }
}
