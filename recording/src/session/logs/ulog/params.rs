//! A ULog's parameters and its sensors' device ids, read in a pass of their own: the parameter
//! messages (`P`: `uint8 key_len`, the key `"type name"`, the value; in the definitions section the
//! parameters at start-up, in the data section the changes) and the `device_id` of the first
//! `sensor_accel` and `sensor_gyro` message of each instance (`multi_id`). PX4's "ULog File
//! Format" (docs.px4.io, `dev_log/ulog_file_format`), as pyulog's `core.py` reads them
//! (`_read_parameters`, `MessageInfo`'s value types).

use super::layout::{parse_format, type_size, Field};
use super::UlogError;
use crate::session::logs::read_exact_or_end;
use crate::session::logs::vehicle::VehicleParams;
use std::collections::HashMap;
use std::io::Read;

/// Where a topic's `device_id` is: its byte offset in a data message's payload (after `msg_id`).
fn device_id_offset(fields: &[Field], formats: &HashMap<String, Vec<Field>>) -> Option<usize> {
    let mut offset = 0usize;
    let mut known = HashMap::new();
    for f in fields {
        if f.name == "device_id" && f.ty == "uint32_t" && f.count == 1 {
            return Some(offset);
        }
        let size = type_size(&f.ty, formats, 0, &mut known)?;
        offset = offset.checked_add(size.checked_mul(f.count)?)?;
    }
    None
}

/// A parameter message's name and value (`int32_t` or `float`; other types are skipped).
fn parameter(p: &[u8]) -> Option<(&str, f64)> {
    let len = usize::from(*p.first()?);
    let key = std::str::from_utf8(p.get(1..1 + len)?).ok()?;
    let (ty, name) = key.split_once(' ')?;
    let v = p.get(1 + len..)?;
    let value = match ty {
        "int32_t" => f64::from(i32::from_le_bytes(v.get(..4)?.try_into().ok()?)),
        "float" => f64::from(f32::from_le_bytes(v.get(..4)?.try_into().ok()?)),
        _ => return None,
    };
    Some((name, value))
}

/// Reads the parameters and device ids of the ULog `r` (its 16-byte header first).
pub fn read_params<R: Read>(mut r: R) -> Result<VehicleParams, UlogError> {
    let mut header = [0u8; 16];
    if !read_exact_or_end(&mut r, &mut header)
        .map_err(|source| UlogError::Io { offset: 0, source })?
    {
        return Err(UlogError::ShortHeader);
    }
    let mut params = VehicleParams::default();
    let mut formats: HashMap<String, Vec<Field>> = HashMap::new();
    // msg_id → (is the accelerometer, multi_id, device_id's offset).
    let mut ids: HashMap<u16, (bool, u8, usize)> = HashMap::new();
    let mut payload = vec![0u8; usize::from(u16::MAX)];
    let mut offset = 16u64;
    loop {
        let mut h = [0u8; 3];
        let size = match read_exact_or_end(&mut r, &mut h) {
            Ok(true) => usize::from(u16::from_le_bytes([h[0], h[1]])),
            // A cut last message costs that message, as the sample reader says.
            Ok(false) => break,
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => break,
            Err(source) => return Err(UlogError::Io { offset, source }),
        };
        match read_exact_or_end(&mut r, &mut payload[..size]) {
            Ok(true) => {}
            Ok(false) if size == 0 => {}
            Ok(false) => break,
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => break,
            Err(source) => return Err(UlogError::Io { offset, source }),
        }
        let p = &payload[..size];
        match h[2] {
            b'F' => {
                if let Some((name, fields)) = parse_format(&String::from_utf8_lossy(p)) {
                    if formats.len() < super::MAX_FORMATS || formats.contains_key(&name) {
                        formats.insert(name, fields);
                    }
                }
            }
            b'A' if p.len() >= 3 => {
                let msg_id = u16::from_le_bytes([p[1], p[2]]);
                let name = String::from_utf8_lossy(&p[3..]);
                let accel = match name.trim_end_matches('\0') {
                    "sensor_accel" => Some(true),
                    "sensor_gyro" => Some(false),
                    _ => None,
                };
                let place = accel.and_then(|a| {
                    let topic = if a { "sensor_accel" } else { "sensor_gyro" };
                    let off = device_id_offset(formats.get(topic)?, &formats)?;
                    Some((a, p[0], off))
                });
                match place {
                    Some(place) => ids.insert(msg_id, place),
                    None => ids.remove(&msg_id),
                };
            }
            b'D' if p.len() >= 2 => {
                let msg_id = u16::from_le_bytes([p[0], p[1]]);
                if let Some(&(accel, multi_id, off)) = ids.get(&msg_id) {
                    let at = 2 + off;
                    if let Some(b) = p.get(at..at + 4) {
                        let id = u32::from_le_bytes(b.try_into().unwrap_or([0; 4]));
                        let map = if accel {
                            &mut params.accel_ids
                        } else {
                            &mut params.gyro_ids
                        };
                        map.entry(multi_id).or_insert(id);
                    }
                }
            }
            b'P' => {
                if let Some((name, value)) = parameter(p) {
                    params.record(name, value);
                }
            }
            _ => {}
        }
        offset += 3 + size as u64;
    }
    Ok(params)
}
