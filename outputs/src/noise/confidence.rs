//! The 1σ of one point of an Allan deviation curve, for plotting it with its error bars (the Python
//! package's `allan`): with `K = n/m` clusters of `m` samples out of `n`, the relative 1σ of the
//! estimated deviation is `1/√(2(K − 1))` (IEEE Std 952-1997, Annex C, eq. C.13; El-Sheimy, Hou and
//! Niu, *Analysis and Modeling of Inertial Sensors Using Allan Variance*, IEEE TIM 57(1), 2008,
//! eq. 13). It is the non-overlapping estimate's; the overlapping one `host noise` computes
//! ([`super::allan::overlapping_adev`]) is somewhat better, so the bounds are conservative.

/// The relative 1σ of the Allan deviation at cluster size `m` from `n` samples; `None` when fewer
/// than two clusters fit (no deviation there).
pub fn relative_sigma(n: usize, m: usize) -> Option<f64> {
    let clusters = n.checked_div(m)?;
    (clusters >= 2).then(|| 1.0 / (2.0 * (clusters as f64 - 1.0)).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_relative_sigma_is_the_standards_formula() {
        // IEEE 952's example: K = 9 clusters give 25 %; 10 000 samples at m = 1 give 0.71 %.
        assert_eq!(relative_sigma(900, 100), Some(0.25));
        assert!((relative_sigma(10_000, 1).unwrap() - 0.007_071).abs() < 1e-6);
        assert_eq!(relative_sigma(100, 60), None);
        assert_eq!(relative_sigma(100, 0), None);
    }
}
