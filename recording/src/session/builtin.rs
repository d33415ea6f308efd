//! The plans shipped in `host/plans/`, built into the binary so that `--plan paper` works anywhere.

use super::plan::{Plan, PlanError};
use std::path::Path;

/// (name, TOML text) of every built-in plan.
pub const BUILTIN_PLANS: [(&str, &str); 9] = [
    ("paper", include_str!("../../plans/paper.toml")),
    ("oblique", include_str!("../../plans/oblique.toml")),
    ("short", include_str!("../../plans/short.toml")),
    (
        "short-oblique",
        include_str!("../../plans/short-oblique.toml"),
    ),
    (
        "quick-oblique",
        include_str!("../../plans/quick-oblique.toml"),
    ),
    ("hand", include_str!("../../plans/hand.toml")),
    (
        "single-package",
        include_str!("../../plans/single-package.toml"),
    ),
    (
        "thermal-soak",
        include_str!("../../plans/thermal-soak.toml"),
    ),
    (
        "thermal-ramp",
        include_str!("../../plans/thermal-ramp.toml"),
    ),
];

/// The built-in plan called `name`, if any.
pub fn builtin_plan(name: &str) -> Option<Result<Plan, PlanError>> {
    BUILTIN_PLANS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, text)| Plan::parse(text))
}

/// The paper's plan (Section 3), the default of `host simulate`.
pub fn paper_plan() -> Plan {
    Plan::parse(BUILTIN_PLANS[0].1).expect("the built-in paper plan is valid (tested)")
}

/// A plan given on the command line: a file if one exists at `spec`, else a built-in plan's name.
pub fn load_plan(spec: &str) -> Result<Plan, PlanError> {
    let path = Path::new(spec);
    if path.exists() {
        return Plan::load(path);
    }
    builtin_plan(spec).unwrap_or_else(|| {
        let names: Vec<&str> = BUILTIN_PLANS.iter().map(|(n, _)| *n).collect();
        Err(PlanError::Io(
            path.to_path_buf(),
            std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!(
                    "no such file, and not a built-in plan (built-in: {})",
                    names.join(", ")
                ),
            ),
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_plans_are_valid_and_shaped_as_documented() {
        for (name, _) in BUILTIN_PLANS {
            let p = builtin_plan(name).unwrap().unwrap();
            assert_eq!(p.sample_rate_hz, 1000.0, "{name}");
        }
        let paper = paper_plan();
        assert_eq!(paper.segments.len(), 15);
        assert_eq!(paper.segments.iter().filter(|s| s.is_static()).count(), 6);
        let oblique = builtin_plan("oblique").unwrap().unwrap();
        assert_eq!(oblique.segments.len(), 24);
        assert!(oblique
            .segments
            .iter()
            .any(|s| s.up_b[0] > 0.7 && s.up_b[1] > 0.7 && s.rate_deg_s == -200.0));
        let hand = builtin_plan("hand").unwrap().unwrap();
        assert_eq!(hand.segments.len(), 24);
        assert!(hand
            .segments
            .iter()
            .all(|s| s.is_static() && s.is_free() && s.duration_s == Some(5.0)));
        let single = builtin_plan("single-package").unwrap().unwrap();
        assert_eq!(single.package, crate::session::Package::Single);
        assert_eq!(single.segments.len(), 15);
        let soak = builtin_plan("thermal-soak").unwrap().unwrap();
        assert!(soak.has_temperature() && soak.segments.len() == 30);
        let ramp = builtin_plan("thermal-ramp").unwrap().unwrap();
        assert!(ramp.segments.iter().all(|s| s.temp_end_c.is_some()));
        assert!(
            shared::chain::Chain(&load_plan("no-such-plan").unwrap_err())
                .to_string()
                .contains("built-in: paper")
        );
    }
}
