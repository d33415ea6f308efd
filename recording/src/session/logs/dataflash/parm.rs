//! ArduPilot's `PARM` messages: the vehicle's parameters, each `Name` (`char[16]`) and `Value`
//! (`float`), written at the start of every log and again when one changes (`AP_Logger`'s
//! `Write_Parameter`, format `QNf` or `QNff` with the default; `LogStructure.h`).

use super::{number, Format};
use crate::session::logs::vehicle::VehicleParams;

/// Records the parameter of one `PARM` message `m` (header included) of format `f`; a message
/// whose name or value does not read is skipped, as the reader skips damaged messages.
pub(super) fn record(f: &Format, m: &[u8], params: &mut VehicleParams) {
    let (Some((name_at, b'N')), Some((value_at, c))) = (f.column("Name"), f.column("Value")) else {
        return;
    };
    let Some(raw) = m.get(name_at..name_at + 16) else {
        return;
    };
    let end = raw.iter().position(|&b| b == 0).unwrap_or(raw.len());
    let Ok(name) = std::str::from_utf8(&raw[..end]) else {
        return;
    };
    if let Some(v) = number(m, value_at, c) {
        params.record(name.trim(), v);
    }
}
