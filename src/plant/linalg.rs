//! Small dense matrices on the stack: the matrix exponential that discretises the linear plants
//! exactly for a zero-order-held input, and a linear solve for their steady states.
//!
//! Only arithmetic is used (no transcendental functions), so results are bit-identical on every
//! target. Sizes are const generics; nothing allocates.

/// A square matrix, rows first.
pub(crate) type Mat<const N: usize> = [[f64; N]; N];

pub(crate) fn identity<const N: usize>() -> Mat<N> {
    let mut m = [[0.0; N]; N];
    for (i, row) in m.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    m
}

pub(crate) fn mul<const N: usize>(a: &Mat<N>, b: &Mat<N>) -> Mat<N> {
    let mut c = [[0.0; N]; N];
    for i in 0..N {
        for k in 0..N {
            let aik = a[i][k];
            if aik == 0.0 {
                continue;
            }
            for j in 0..N {
                c[i][j] += aik * b[k][j];
            }
        }
    }
    c
}

pub(crate) fn mul_vec<const N: usize>(a: &Mat<N>, x: &[f64; N]) -> [f64; N] {
    let mut y = [0.0; N];
    for (yi, row) in y.iter_mut().zip(a) {
        *yi = row.iter().zip(x).map(|(r, v)| r * v).sum();
    }
    y
}

/// `e^A` by scaling and squaring with a Taylor series: A is scaled by 2^-s until its ∞-norm is
/// at most 1/2, where 20 terms leave a truncation error below 1e-25 relative, then squared s
/// times.
pub(crate) fn expm<const N: usize>(a: &Mat<N>) -> Mat<N> {
    let norm = a
        .iter()
        .map(|row| row.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let mut squarings = 0u32;
    let mut scale = 1.0;
    while norm * scale > 0.5 && squarings < 1000 {
        scale *= 0.5;
        squarings += 1;
    }
    let mut scaled = *a;
    for row in scaled.iter_mut() {
        for v in row.iter_mut() {
            *v *= scale;
        }
    }
    // Horner form of Σ Aᵏ/k!: I + A/1·(I + A/2·(I + … (I + A/20))).
    let mut result = identity::<N>();
    for k in (1..=20).rev() {
        let mut term = mul(&scaled, &result);
        let inv_k = 1.0 / f64::from(k);
        for (i, row) in term.iter_mut().enumerate() {
            for v in row.iter_mut() {
                *v *= inv_k;
            }
            row[i] += 1.0;
        }
        result = term;
    }
    for _ in 0..squarings {
        result = mul(&result, &result);
    }
    result
}

/// Exact zero-order-hold discretisation of ẋ = A·x + B·u over `dt_s`: x[k+1] = Φ·x[k] + Γ·u[k].
///
/// Uses the augmented exponential exp([[A, B], [0, 0]]·dt) = [[Φ, Γ], [0, I]], which needs no
/// inverse of A (so an integrator in A is fine). `K` must equal `N + M`.
///
/// # Panics
///
/// If `K != N + M` (a bug in the caller, fixed at compile time in practice).
pub(crate) fn zoh<const N: usize, const M: usize, const K: usize>(
    a: &Mat<N>,
    b: &[[f64; M]; N],
    dt_s: f64,
) -> (Mat<N>, [[f64; M]; N]) {
    assert_eq!(K, N + M, "augmented size must be N + M");
    let mut aug = [[0.0; K]; K];
    for i in 0..N {
        for j in 0..N {
            aug[i][j] = a[i][j] * dt_s;
        }
        for j in 0..M {
            aug[i][N + j] = b[i][j] * dt_s;
        }
    }
    let e = expm(&aug);
    let mut phi = [[0.0; N]; N];
    let mut gamma = [[0.0; M]; N];
    for i in 0..N {
        phi[i].copy_from_slice(&e[i][..N]);
        gamma[i].copy_from_slice(&e[i][N..]);
    }
    (phi, gamma)
}

/// Solves A·x = b by Gaussian elimination with partial pivoting; `None` if A is singular to
/// working precision.
pub(crate) fn solve<const N: usize>(a: &Mat<N>, b: &[f64; N]) -> Option<[f64; N]> {
    let mut m = *a;
    let mut x = *b;
    let scale = m
        .iter()
        .flat_map(|row| row.iter())
        .fold(0.0f64, |acc, v| acc.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return None;
    }
    for col in 0..N {
        let pivot = (col..N).max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))?;
        if m[pivot][col].abs() <= scale * 1e-14 {
            return None;
        }
        m.swap(col, pivot);
        x.swap(col, pivot);
        for row in col + 1..N {
            let factor = m[row][col] / m[col][col];
            if factor == 0.0 {
                continue;
            }
            let pivot_row = m[col];
            for (dst, src) in m[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *dst -= factor * src;
            }
            x[row] -= factor * x[col];
        }
    }
    for col in (0..N).rev() {
        let mut sum = x[col];
        for k in col + 1..N {
            sum -= m[col][k] * x[k];
        }
        x[col] = sum / m[col][col];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponential_of_a_diagonal_matrix_is_elementwise() {
        let e = expm(&[[-1.0, 0.0], [0.0, 2.0]]);
        assert!((e[0][0] - (-1.0f64).exp()).abs() < 1e-14);
        assert!((e[1][1] - 2.0f64.exp()).abs() < 1e-13);
        assert_eq!(e[0][1], 0.0);
    }

    #[test]
    fn exponential_of_a_rotation_generator_is_a_rotation() {
        let w = 3.0;
        let e = expm(&[[0.0, -w], [w, 0.0]]);
        assert!((e[0][0] - w.cos()).abs() < 1e-13);
        assert!((e[1][0] - w.sin()).abs() < 1e-13);
    }

    #[test]
    fn zero_order_hold_of_an_integrator_is_dt() {
        let (phi, gamma) = zoh::<1, 1, 2>(&[[0.0]], &[[1.0]], 0.25);
        assert_eq!(phi[0][0], 1.0);
        assert!((gamma[0][0] - 0.25).abs() < 1e-15);
    }

    #[test]
    fn zero_order_hold_of_a_first_order_lag_matches_the_closed_form() {
        let tau = 0.1;
        let dt = 0.01;
        let (phi, gamma) = zoh::<1, 1, 2>(&[[-1.0 / tau]], &[[1.0 / tau]], dt);
        let a = (-dt / tau).exp();
        assert!((phi[0][0] - a).abs() < 1e-15);
        assert!((gamma[0][0] - (1.0 - a)).abs() < 1e-15);
    }

    #[test]
    fn solve_recovers_a_known_solution_and_rejects_a_singular_matrix() {
        let a = [[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]];
        let x = [1.0, -2.0, 3.0];
        let b = mul_vec(&a, &x);
        let y = solve(&a, &b).unwrap();
        for (u, v) in x.iter().zip(y) {
            assert!((u - v).abs() < 1e-12);
        }
        assert!(solve(&[[1.0, 2.0], [2.0, 4.0]], &[1.0, 1.0]).is_none());
    }
}
