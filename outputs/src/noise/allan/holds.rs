//! Whether the fitted noise figures hold (docs/tools.md, `host noise`): a term counts only where
//! the curve reaches the τ that shows it, a term fitted far below zero is a model misfit, and the
//! fitted curve passes its points within their 1σ or says it does not.

use super::{basis, point_sd, NoiseTerms, VarPoint};
use serde::{Deserialize, Serialize};

/// A term fitted this many times its 1σ below zero is named a model misfit (the mirror of
/// `super::Z_DETERMINED`: as rare on a curve the model describes as a false term).
pub const Z_MISFIT: f64 = 3.0;

/// A point this many times its 1σ from the fitted curve means the curve does not describe the
/// measured points (about one point in 16 000 on a curve the model describes).
pub const Z_CURVE: f64 = 4.0;

/// How the fitted curve passes the points it was fitted to, each with its 1σ from the equivalent
/// degrees of freedom under the fitted terms.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CurveCheck {
    /// Points fitted.
    pub points: usize,
    /// Of them, those the fitted curve passes within their 1σ (about two in three when it holds).
    pub within_1sigma: usize,
    /// The point furthest from the curve: its τ, s.
    pub worst_tau_s: f64,
    /// The fitted curve's deviation there over the measured one.
    pub worst_ratio: f64,
    /// That point's distance from the curve in its 1σ (of the Allan variance), signed: measured
    /// above the curve is positive.
    pub worst_z: f64,
    /// Whether the curve describes the points: none further than [`Z_CURVE`] times its 1σ.
    pub holds: bool,
}

impl NoiseTerms {
    /// What a reader must know beside the figures of axis `axis`: each term fitted far below zero
    /// (a model misfit), each significant term the record ends before, and a fitted curve that
    /// does not pass the measured points. Empty when the figures hold.
    pub fn notes(&self, axis: &str) -> Vec<String> {
        let mut out = Vec::new();
        for (name, fit) in ["N", "B", "K"].iter().zip(&self.fits) {
            if fit.misfit {
                out.push(format!(
                    "{axis} {name}: fitted at {:.1}σ, far below zero (no noise has a negative \
                     variance): a model misfit, the curve has a shape white noise, bias instability \
                     and random walk together cannot make; the other figures of {axis} are not \
                     reliable",
                    fit.significance
                ));
            }
            if fit.beyond_record {
                let at = fit.shows_at_tau_s.map_or(String::new(), |t| {
                    format!(" (it would show from τ ≈ {t:.3} s)")
                });
                out.push(format!(
                    "{axis} {name}: {:.1}σ, but the curve does not reach the τ that shows it{at}: \
                     not determined by this recording",
                    fit.significance
                ));
            }
        }
        if let Some(c) = self.curve.filter(|c| !c.holds) {
            out.push(format!(
                "{axis}: the fitted curve misses the measured points: at τ = {:.3} s it is {:.2}× \
                 the measured deviation ({:.1}σ of that point); {} of {} points within their 1σ. \
                 The terms of {axis} describe this curve badly",
                c.worst_tau_s, c.worst_ratio, c.worst_z, c.within_1sigma, c.points
            ));
        }
        out
    }
}

/// The contribution of each term `idx[r]` to the Allan variance at `tau`.
fn shares(tau: f64, idx: &[usize], coef: &[f64]) -> Vec<f64> {
    let b = basis(tau);
    idx.iter().zip(coef).map(|(&i, c)| b[i] * c).collect()
}

/// Term `r`'s share of the model's Allan variance at `tau`.
fn share(tau: f64, idx: &[usize], coef: &[f64], r: usize) -> f64 {
    let v = shares(tau, idx, coef);
    let total: f64 = v.iter().map(|x| x.max(0.0)).sum();
    if total > 0.0 {
        v[r].max(0.0) / total
    } else {
        0.0
    }
}

/// The τ the search for a term's largest share covers: every half octave from 2⁻⁴⁰ of the
/// curve's first τ to 2⁴⁰ times its last.
fn wide_taus(lo: f64, hi: f64) -> impl Iterator<Item = f64> {
    let (a, b) = (
        lo.ln() - 40.0 * std::f64::consts::LN_2,
        hi.ln() + 40.0 * std::f64::consts::LN_2,
    );
    let steps = ((b - a) / (0.5 * std::f64::consts::LN_2)).ceil() as usize;
    (0..=steps).map(move |k| (a + (b - a) * k as f64 / steps as f64).exp())
}

/// The first of the fitted terms the curve does not show, and the τ nearest the curve where it
/// would. A term shows where its share of the Allan variance is at least half the largest share it
/// has at any τ: white noise at the short τ, a random walk at the long, a bias instability about
/// the curve's floor (`τ = √3 N/K` with both), however small its share there. A fit can find a term
/// significant from a curve that never reaches that τ (a short still's "bias instability"); it is
/// then a guess at the curve's end, not a figure of the recording.
pub(super) fn unshown(
    pts: &[VarPoint],
    idx: &[usize],
    coef: &[f64],
) -> Option<(usize, Option<f64>)> {
    let (lo, hi) = (pts.first()?.tau, pts.last()?.tau);
    let largest = |r: usize| {
        wide_taus(lo, hi)
            .map(|t| share(t, idx, coef, r))
            .fold(0.0, f64::max)
    };
    let r = (0..idx.len()).find(|&r| {
        let half = 0.5 * largest(r);
        !pts.iter().any(|p| share(p.tau, idx, coef, r) >= half)
    })?;
    let half = 0.5 * largest(r);
    let shows_at = (1..=80)
        .flat_map(|k| {
            let f = 2f64.powf(0.5 * k as f64);
            [hi * f, lo / f]
        })
        .find(|&tau| share(tau, idx, coef, r) >= half);
    Some((r, shows_at))
}

/// How the curve of the terms `idx` at `coef` passes the points (see [`CurveCheck`]).
pub(super) fn curve_check(pts: &[VarPoint], idx: &[usize], coef: &[f64]) -> Option<CurveCheck> {
    if idx.is_empty() || pts.is_empty() {
        return None;
    }
    let mut out = CurveCheck {
        points: pts.len(),
        holds: true,
        ..CurveCheck::default()
    };
    for p in pts {
        let model: f64 = shares(p.tau, idx, coef).iter().sum();
        let z = (p.var - model) / point_sd(p, idx, coef);
        out.within_1sigma += usize::from(z.abs() <= 1.0);
        if z.is_nan() || z.abs() > out.worst_z.abs() {
            out.worst_z = z;
            out.worst_tau_s = p.tau;
            out.worst_ratio = (model.max(0.0) / p.var).sqrt();
        }
    }
    out.holds = out.worst_z.abs() <= Z_CURVE;
    Some(out)
}
