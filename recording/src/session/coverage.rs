//! How well a hand-held session's still positions serve a calibration: how many are distinct,
//! which body directions none comes near, and whether they are the six faces of a cube
//! (`docs/model.md` §7.1) — the check `host segment` makes before cutting a session.

use super::segment::{
    angle_deg, Interval, PositionSet, SegmentError, FACE_COVERAGE_DEG, FACE_LABEL_DEG,
    MIN_POSITIONS, RECOMMENDED_POSITIONS, SIX_FACE_DEG,
};

/// How well a set of still positions serves a calibration.
#[derive(Clone, Debug, PartialEq)]
pub struct Coverage {
    /// Distinct positions (closer than the same-position angle count once).
    pub distinct: usize,
    /// For each still interval, the earlier one it repeats, if any.
    pub repeats: Vec<Option<usize>>,
    /// Body directions (+x, −x, …) with no position within [`FACE_COVERAGE_DEG`].
    pub missing_faces: Vec<&'static str>,
    /// A six-face session's face for each still interval (its body axis up), when the positions
    /// are the six faces of a cube (`six_face_labels`).
    pub faces: Option<Vec<[f64; 3]>>,
}

const FACES: [(&str, [f64; 3]); 6] = [
    ("x up", [1.0, 0.0, 0.0]),
    ("x down", [-1.0, 0.0, 0.0]),
    ("y up", [0.0, 1.0, 0.0]),
    ("y down", [0.0, -1.0, 0.0]),
    ("z up", [0.0, 0.0, 1.0]),
    ("z down", [0.0, 0.0, -1.0]),
];

/// Distinct positions and the directions they miss.
pub fn coverage(stills: &[Interval], same_position_deg: f64) -> Coverage {
    let mut firsts: Vec<usize> = Vec::new();
    let repeats = stills
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let earlier = firsts
                .iter()
                .copied()
                .find(|&f| angle_deg(&stills[f].direction, &s.direction) < same_position_deg);
            if earlier.is_none() {
                firsts.push(k);
            }
            earlier
        })
        .collect();
    let missing_faces = FACES
        .iter()
        .filter(|(_, axis)| {
            stills
                .iter()
                .all(|s| angle_deg(&s.direction, axis) > FACE_COVERAGE_DEG)
        })
        .map(|(name, _)| *name)
        .collect();
    Coverage {
        distinct: firsts.len(),
        repeats,
        missing_faces,
        faces: six_face_labels(stills),
    }
}

/// The faces of a six-face session (docs/model.md §7.1), as a consumer MEMS unit shows them: each
/// still interval labelled by its nearest body axis (within `FACE_LABEL_DEG`), all six present;
/// each axis's bias and scale from the mean outputs of its two faces; and every interval, with
/// those taken out, within [`SIX_FACE_DEG`] of its label. Raw directions against a tight bound would
/// refuse a unit whose biases alone tilt a face by more than its placement.
pub fn six_face_labels(stills: &[Interval]) -> Option<Vec<[f64; 3]>> {
    let labels: Vec<(usize, f64)> = stills
        .iter()
        .map(|s| {
            let d = s.direction;
            let j = (0..3).max_by(|&a, &b| d[a].abs().total_cmp(&d[b].abs()))?;
            let mut axis = [0.0; 3];
            axis[j] = d[j].signum();
            (angle_deg(&d, &axis) < FACE_LABEL_DEG).then_some((j, d[j].signum()))
        })
        .collect::<Option<_>>()?;
    checked_faces(stills, &labels).ok()
}

/// The six faces' names, in [`face_label`]'s order.
const FACE_NAMES: [&str; 6] = ["x+", "x-", "y+", "y-", "z+", "z-"];

/// A face's label (`x+` … `z-`, also `+x` or `x up`) as its axis and sign.
pub fn face_label(text: &str) -> Option<(usize, f64)> {
    let t = text.trim().to_ascii_lowercase().replace(' ', "");
    let (axis, sign) = match t.as_str() {
        "x+" | "+x" | "xup" => (0, 1.0),
        "x-" | "-x" | "xdown" => (0, -1.0),
        "y+" | "+y" | "yup" => (1, 1.0),
        "y-" | "-y" | "ydown" => (1, -1.0),
        "z+" | "+z" | "zup" => (2, 1.0),
        "z-" | "-z" | "zdown" => (2, -1.0),
        _ => return None,
    };
    Some((axis, sign))
}

/// The faces the user labelled (one label per still interval, in order; [`face_label`]),
/// checked against the data as the found ones are: all six present, and every interval, with the
/// faces' own biases and scales taken out, within [`SIX_FACE_DEG`] of its label.
pub fn given_faces(
    stills: &[Interval],
    labels: &[(usize, f64)],
) -> Result<Vec<[f64; 3]>, SegmentError> {
    if labels.len() != stills.len() {
        return Err(SegmentError::FaceLabelCount {
            given: labels.len(),
            found: stills.len(),
        });
    }
    checked_faces(stills, labels).map_err(|e| match e {
        FaceCheck::Missing(name) => SegmentError::FaceMissing(name),
        FaceCheck::Off(k, angle_deg) => SegmentError::FaceLabelContradicted {
            still: k + 1,
            label: name_of(labels[k]),
            direction: stills[k].direction,
            angle_deg,
        },
    })
}

fn name_of((j, sign): (usize, f64)) -> &'static str {
    FACE_NAMES[2 * j + usize::from(sign < 0.0)]
}

/// Why labelled faces do not hold.
enum FaceCheck {
    /// No interval is labelled this face.
    Missing(&'static str),
    /// Interval `k` is this far from its label (degrees), biases and scales taken out.
    Off(usize, f64),
}

/// Each axis's bias and scale from the mean outputs of its two labelled faces, then every interval
/// within [`SIX_FACE_DEG`] of its label with those taken out.
fn checked_faces(stills: &[Interval], labels: &[(usize, f64)]) -> Result<Vec<[f64; 3]>, FaceCheck> {
    let mean = |j: usize, sign: f64| {
        let v: Vec<f64> = stills
            .iter()
            .zip(labels)
            .filter(|(_, l)| **l == (j, sign))
            .map(|(s, _)| s.mean_acc[j])
            .collect();
        (!v.is_empty())
            .then(|| v.iter().sum::<f64>() / v.len() as f64)
            .ok_or(FaceCheck::Missing(name_of((j, sign))))
    };
    let mut bias = [0.0; 3];
    let mut scale = [0.0; 3];
    for j in 0..3 {
        let (up, down) = (mean(j, 1.0)?, mean(j, -1.0)?);
        bias[j] = 0.5 * (up + down);
        scale[j] = 0.5 * (up - down);
    }
    let faces: Vec<[f64; 3]> = labels
        .iter()
        .map(|&(j, sign)| {
            let mut a = [0.0; 3];
            a[j] = sign;
            a
        })
        .collect();
    for (k, (s, face)) in stills.iter().zip(&faces).enumerate() {
        let c: [f64; 3] = core::array::from_fn(|i| (s.mean_acc[i] - bias[i]) / scale[i]);
        let n = shared::linalg::norm(&c);
        let off = if n > 0.0 && scale.iter().all(|&x| x > 0.0) {
            angle_deg(&c.map(|x| x / n), face)
        } else {
            180.0
        };
        if off.is_nan() || off >= SIX_FACE_DEG {
            return Err(FaceCheck::Off(k, off));
        }
    }
    Ok(faces)
}

impl Coverage {
    /// Refuses fewer than [`MIN_POSITIONS`] distinct positions that are not the six faces of a cube,
    /// saying how many more of which kind.
    pub fn check(&self, found: usize, same_position_deg: f64) -> Result<PositionSet, SegmentError> {
        if self.distinct >= MIN_POSITIONS {
            return Ok(PositionSet::Spread);
        }
        if self.faces.is_some() {
            return Ok(PositionSet::SixFaces);
        }
        Err(SegmentError::TooFewPositions {
            found,
            distinct: self.distinct,
            more: MIN_POSITIONS - self.distinct,
            same_deg: same_position_deg,
            faces: self.faces_text(),
        })
    }

    /// "; include x down, z up" or "".
    pub(crate) fn faces_text(&self) -> String {
        if self.missing_faces.is_empty() {
            String::new()
        } else {
            format!(
                "; include positions with {} (no position within {FACE_COVERAGE_DEG:.0}° of them yet)",
                self.missing_faces.join(", ")
            )
        }
    }

    /// Advice when the positions suffice but are fewer than recommended or leave directions out.
    pub fn advice(&self) -> Option<String> {
        if self.distinct >= RECOMMENDED_POSITIONS && self.missing_faces.is_empty() {
            return None;
        }
        let more = RECOMMENDED_POSITIONS
            .saturating_sub(self.distinct)
            .max(self.missing_faces.len());
        let (gap, including) = if self.missing_faces.is_empty() {
            (String::new(), "")
        } else {
            (
                format!(
                    ", and none within {FACE_COVERAGE_DEG:.0}° of {}",
                    self.missing_faces.join(", ")
                ),
                " (those directions included)",
            )
        };
        Some(format!(
            "{} distinct positions ({RECOMMENDED_POSITIONS} recommended){gap}: recording {more} \
             more, spread over the whole sphere{including}, would make the calibration more robust",
            self.distinct
        ))
    }
}
