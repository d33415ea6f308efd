//! What a ULog's format definitions say: each field's type and place in a message, and the layout
//! of the IMU topics read (`sensor_accel`, `sensor_gyro`, `sensor_combined`), nested types sized and
//! bounded.

use super::UlogError;
use std::collections::HashMap;

/// Deepest nesting of a format inside another.
pub(super) const MAX_NESTING: usize = 8;

/// A field of a format: type, array length (1 for a scalar), name.
#[derive(Clone, Debug)]
pub(super) struct Field {
    pub(super) ty: String,
    pub(super) count: usize,
    pub(super) name: String,
}

/// Parses "name:type field;type[n] field;…" into the name and its fields.
pub(super) fn parse_format(text: &str) -> Option<(String, Vec<Field>)> {
    let (name, rest) = text.split_once(':')?;
    let mut fields = Vec::new();
    for part in rest.split(';').filter(|p| !p.trim().is_empty()) {
        let (ty, field) = part.trim().split_once(' ')?;
        let (ty, count) = match ty.split_once('[') {
            Some((t, n)) => (t, n.strip_suffix(']')?.parse::<usize>().ok()?),
            None => (ty, 1),
        };
        if count == 0 || count > u16::MAX as usize {
            return None;
        }
        fields.push(Field {
            ty: ty.to_string(),
            count,
            name: field.trim().to_string(),
        });
    }
    Some((name.to_string(), fields))
}

/// The size in bytes of a basic type.
pub(super) fn basic_size(ty: &str) -> Option<usize> {
    Some(match ty {
        "int8_t" | "uint8_t" | "bool" | "char" => 1,
        "int16_t" | "uint16_t" => 2,
        "int32_t" | "uint32_t" | "float" => 4,
        "int64_t" | "uint64_t" | "double" => 8,
        _ => return None,
    })
}

/// The size of a type, basic or a nested format; `known` remembers the nested formats' sizes, so that
/// a damaged log of many fields of deeply nested types costs no more than its fields.
pub(super) fn type_size(
    ty: &str,
    formats: &HashMap<String, Vec<Field>>,
    depth: usize,
    known: &mut HashMap<String, Option<usize>>,
) -> Option<usize> {
    if let Some(n) = basic_size(ty) {
        return Some(n);
    }
    if depth >= MAX_NESTING {
        return None;
    }
    if let Some(&n) = known.get(ty) {
        return n;
    }
    let n = formats.get(ty).and_then(|fields| {
        fields.iter().try_fold(0usize, |sum, f| {
            sum.checked_add(type_size(&f.ty, formats, depth + 1, known)?.checked_mul(f.count)?)
        })
    });
    known.insert(ty.to_string(), n);
    n
}

/// Where a field is: its byte offset in the payload (after `msg_id`), its type.
#[derive(Clone, Copy, Debug)]
pub(super) struct Place {
    pub(super) offset: usize,
    pub(super) ty: Scalar,
}

#[derive(Clone, Copy, Debug)]
pub(super) enum Scalar {
    U64,
    I32,
    F32,
}

impl Place {
    pub(super) fn end(self) -> usize {
        self.offset
            + match self.ty {
                Scalar::U64 => 8,
                Scalar::I32 | Scalar::F32 => 4,
            }
    }

    pub(super) fn read(self, d: &[u8]) -> f64 {
        let b = |n: usize| &d[self.offset..self.offset + n];
        match self.ty {
            Scalar::U64 => u64::from_le_bytes(b(8).try_into().unwrap_or([0; 8])) as f64,
            Scalar::I32 => i32::from_le_bytes(b(4).try_into().unwrap_or([0; 4])) as f64,
            Scalar::F32 => f32::from_le_bytes(b(4).try_into().unwrap_or([0; 4])) as f64,
        }
    }
}

/// The IMU topics this reader takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Topic {
    Combined,
    Accel,
    Gyro,
}

impl Topic {
    pub(super) fn from_name(name: &str) -> Option<Topic> {
        match name {
            "sensor_combined" => Some(Topic::Combined),
            "sensor_accel" => Some(Topic::Accel),
            "sensor_gyro" => Some(Topic::Gyro),
            _ => None,
        }
    }

    pub(super) fn name(self) -> &'static str {
        match self {
            Topic::Combined => "sensor_combined",
            Topic::Accel => "sensor_accel",
            Topic::Gyro => "sensor_gyro",
        }
    }
}

/// A subscribed IMU topic's field places.
#[derive(Clone, Debug)]
pub(super) struct Layout {
    pub(super) topic: Topic,
    pub(super) time: Place,
    /// `timestamp_sample` where logged (the sensor's own sample time).
    pub(super) sample_time: Option<Place>,
    /// sensor_combined: the accelerometer's time offset.
    pub(super) relative: Option<Place>,
    /// x, y, z (sensor_combined: the accelerometer's).
    pub(super) xyz: [Place; 3],
    /// sensor_combined: the gyro's.
    pub(super) gyro: Option<[Place; 3]>,
    pub(super) temperature: Option<Place>,
    pub(super) need: usize,
}

/// The byte offsets of a format's top-level fields, by name (arrays: `name[i]`).
pub(super) fn places(
    fields: &[Field],
    formats: &HashMap<String, Vec<Field>>,
) -> Option<HashMap<String, Place>> {
    let mut out = HashMap::new();
    let mut offset = 0usize;
    let mut known = HashMap::new();
    for f in fields {
        let size = type_size(&f.ty, formats, 0, &mut known)?;
        let scalar = match f.ty.as_str() {
            "uint64_t" => Some(Scalar::U64),
            "int32_t" => Some(Scalar::I32),
            "float" => Some(Scalar::F32),
            _ => None,
        };
        for i in 0..f.count {
            if let Some(ty) = scalar {
                let name = if f.count == 1 {
                    f.name.clone()
                } else {
                    format!("{}[{i}]", f.name)
                };
                out.insert(name, Place { offset, ty });
            }
            offset = offset.checked_add(size)?;
        }
    }
    Some(out)
}

pub(super) fn layout(
    topic: Topic,
    fields: &[Field],
    formats: &HashMap<String, Vec<Field>>,
    offset: u64,
) -> Result<Layout, UlogError> {
    let p = places(fields, formats).ok_or_else(|| UlogError::UnknownType {
        offset,
        topic: topic.name().into(),
        ty: fields
            .iter()
            .find(|f| type_size(&f.ty, formats, 0, &mut HashMap::new()).is_none())
            .map_or(String::new(), |f| f.ty.clone()),
    })?;
    let get = |field: &'static str| {
        p.get(field)
            .copied()
            .ok_or_else(|| UlogError::MissingField {
                offset,
                topic: topic.name().into(),
                field,
                format: fields
                    .iter()
                    .map(|f| format!("{} {}", f.ty, f.name))
                    .collect::<Vec<_>>()
                    .join("; "),
            })
    };
    let three = |base: &'static str| -> Result<[Place; 3], UlogError> {
        let names: [&'static str; 3] = match base {
            "accelerometer_m_s2" => [
                "accelerometer_m_s2[0]",
                "accelerometer_m_s2[1]",
                "accelerometer_m_s2[2]",
            ],
            "gyro_rad" => ["gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]"],
            _ => ["x", "y", "z"],
        };
        Ok([get(names[0])?, get(names[1])?, get(names[2])?])
    };
    let time = get("timestamp")?;
    let l = match topic {
        Topic::Combined => Layout {
            topic,
            time,
            sample_time: None,
            relative: Some(get("accelerometer_timestamp_relative")?),
            xyz: three("accelerometer_m_s2")?,
            gyro: Some(three("gyro_rad")?),
            temperature: None,
            need: 0,
        },
        Topic::Accel | Topic::Gyro => Layout {
            topic,
            time,
            sample_time: p.get("timestamp_sample").copied(),
            relative: None,
            xyz: three("xyz")?,
            gyro: None,
            temperature: p.get("temperature").copied(),
            need: 0,
        },
    };
    let need = [Some(l.time), l.sample_time, l.relative, l.temperature]
        .into_iter()
        .flatten()
        .chain(l.xyz)
        .chain(l.gyro.into_iter().flatten())
        .map(Place::end)
        .max()
        .unwrap_or(0);
    Ok(Layout { need, ..l })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_format_definition_parses_with_arrays_and_padding() {
        let (name, f) = parse_format(
            "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint8_t[4] _padding0;",
        )
        .unwrap();
        assert_eq!(name, "sensor_combined");
        assert_eq!(f.len(), 3);
        assert_eq!((f[1].ty.as_str(), f[1].count), ("float", 3));
        let formats = HashMap::new();
        let p = places(&f, &formats).unwrap();
        assert_eq!(p["gyro_rad[2]"].offset, 16);
        assert!(parse_format("no colon").is_none());
        assert!(parse_format("x:float[0] a;").is_none());
    }

    /// A log that keeps sensor_accel/sensor_gyro only for comparison (a few samples) and
    /// sensor_combined at the estimator's rate is read from sensor_combined, and says so.
    #[test]
    fn nested_types_are_sized_and_a_loop_is_refused() {
        let mut formats = HashMap::new();
        formats.insert(
            "inner".to_string(),
            parse_format("inner:double a;uint8_t b;").unwrap().1,
        );
        let mut known = HashMap::new();
        assert_eq!(type_size("inner", &formats, 0, &mut known), Some(9));
        formats.insert("loop".to_string(), parse_format("loop:loop a;").unwrap().1);
        assert_eq!(type_size("loop", &formats, 0, &mut HashMap::new()), None);
    }
}
