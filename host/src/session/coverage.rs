//! How well a hand-held session's still positions serve a calibration: how many are distinct,
//! which body directions none comes near, and whether they are the six faces of a cube
//! (`docs/model.md` §7.1) — the check `host segment` makes before cutting a session.

use super::segment::{
    angle_deg, Interval, PositionSet, SegmentError, FACE_COVERAGE_DEG, MIN_POSITIONS,
    RECOMMENDED_POSITIONS, SIX_FACE_DEG,
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
    /// Every position within [`SIX_FACE_DEG`] of a body axis, and all six axes' directions present.
    pub six_faces: bool,
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
pub(crate) fn coverage(stills: &[Interval], same_position_deg: f64) -> Coverage {
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
    let near_face = |s: &Interval| {
        FACES
            .iter()
            .position(|(_, a)| angle_deg(&s.direction, a) < SIX_FACE_DEG)
    };
    let faces: Vec<Option<usize>> = stills.iter().map(near_face).collect();
    let six_faces =
        faces.iter().all(Option::is_some) && (0..FACES.len()).all(|f| faces.contains(&Some(f)));
    Coverage {
        distinct: firsts.len(),
        repeats,
        missing_faces,
        six_faces,
    }
}

impl Coverage {
    /// Refuses fewer than [`MIN_POSITIONS`] distinct positions that are not the six faces of a cube,
    /// saying how many more of which kind.
    pub fn check(&self, found: usize, same_position_deg: f64) -> Result<PositionSet, SegmentError> {
        if self.distinct >= MIN_POSITIONS {
            return Ok(PositionSet::Spread);
        }
        if self.six_faces {
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
