//! A TOML file's arrays checked against what serde kept of them: the plan and the calibration file
//! both read fixed-size arrays, and serde drops a longer array's surplus without a word.

use serde::Serialize;

/// An array in the text longer than the field that read it.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("'{path}' has {given} values, {expected} expected; remove the extra ones")]
pub struct SurplusValues {
    /// Where the array is: its table, key and indices (`static.zero_bias_v`, `gyro.matrix[0]`).
    pub path: String,
    /// The values the text has.
    pub given: usize,
    /// The values the field takes.
    pub expected: usize,
}

/// Arrays in `text` longer than what `parsed` kept: serde fills a `[f64; 3]` from the first three
/// values of a longer array and drops the rest silently (`zero_bias_v = [a, b, c, d]`, a 3×4 matrix,
/// `up_b = [1, 0, 0, 7]`). `parsed` is serialised back and every array's length compared with the
/// text's; the first that differs is named.
pub fn surplus_values<T: Serialize>(text: &str, parsed: &T) -> Option<SurplusValues> {
    let original: toml::Value = toml::from_str(text).ok()?;
    let kept = toml::Value::try_from(parsed).ok()?;
    first_length_difference(&original, &kept, "")
}

fn first_length_difference(a: &toml::Value, b: &toml::Value, path: &str) -> Option<SurplusValues> {
    match (a, b) {
        (toml::Value::Table(ta), toml::Value::Table(tb)) => ta.iter().find_map(|(k, va)| {
            let p = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            tb.get(k).and_then(|vb| first_length_difference(va, vb, &p))
        }),
        (toml::Value::Array(xa), toml::Value::Array(xb)) => {
            if xa.len() != xb.len() {
                return Some(SurplusValues {
                    path: path.to_string(),
                    given: xa.len(),
                    expected: xb.len(),
                });
            }
            xa.iter()
                .zip(xb)
                .enumerate()
                .find_map(|(i, (va, vb))| first_length_difference(va, vb, &format!("{path}[{i}]")))
        }
        _ => None,
    }
}
