//! The `sensor_msgs/msg/Imu` message in CDR, decoded by hand: a CDR decoder crate would be a
//! general serde layer for one fixed message of plain numbers, and the layout is short and fixed
//! by the message definition (`sensor_msgs/msg/Imu.msg`, `std_msgs/msg/Header.msg`,
//! `builtin_interfaces/msg/Time.msg`).

/// What is wrong with a CDR message.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CdrError {
    /// Shorter than its fields.
    #[error("{len} bytes end inside the field '{field}'")]
    Short {
        /// The message's length.
        len: usize,
        /// The field.
        field: &'static str,
    },
    /// An encapsulation other than plain CDR.
    #[error("encapsulation {0:#06x} is not plain CDR (0x0000 big-, 0x0001 little-endian)")]
    Encapsulation(u16),
}

/// An Imu message's time (s), angular velocity (rad/s) and linear acceleration (m/s²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuMessage {
    /// `header.stamp` in seconds.
    pub stamp_s: f64,
    /// `angular_velocity`, rad/s.
    pub gyro_rad_s: [f64; 3],
    /// `linear_acceleration`, m/s².
    pub acc_m_s2: [f64; 3],
}

/// Decodes a CDR-serialised `sensor_msgs/msg/Imu`.
///
/// The encoding is OMG plain CDR (XCDR version 1; DDS-XTypes 1.3 §7.4.1.1, the CORBA 3.4 Part 2
/// §9.3 rules), as ROS 2's rmw layers write it: a 4-byte encapsulation header (`00 00` big-endian,
/// `00 01` little-endian, then two option bytes), then the fields in order, each primitive aligned
/// to its own size counted from the end of the encapsulation header; a string is a `u32` length that
/// counts its terminating NUL, then its bytes. The message: `header` (`stamp.sec` i32,
/// `stamp.nanosec` u32, `frame_id` string), `orientation` (4 × f64), its covariance (9 × f64),
/// `angular_velocity` (3 × f64), its covariance, `linear_acceleration` (3 × f64), its covariance.
pub fn decode_imu(m: &[u8]) -> Result<ImuMessage, CdrError> {
    let head = m.get(..4).ok_or(CdrError::Short {
        len: m.len(),
        field: "encapsulation",
    })?;
    let kind = u16::from_be_bytes([head[0], head[1]]);
    let little = match kind {
        0x0000 => false,
        0x0001 => true,
        other => return Err(CdrError::Encapsulation(other)),
    };
    let mut c = Cdr {
        body: &m[4..],
        pos: 0,
        little,
        len: m.len(),
    };
    let sec = c.u32("header.stamp.sec")? as i32;
    let nanosec = c.u32("header.stamp.nanosec")?;
    let len = c.u32("header.frame_id")? as usize;
    c.take(len, 1, "header.frame_id")?;
    c.f64s::<4>("orientation")?;
    c.f64s::<9>("orientation_covariance")?;
    let w = c.f64s::<3>("angular_velocity")?;
    c.f64s::<9>("angular_velocity_covariance")?;
    let a = c.f64s::<3>("linear_acceleration")?;
    Ok(ImuMessage {
        stamp_s: f64::from(sec) + f64::from(nanosec) * 1e-9,
        gyro_rad_s: w,
        acc_m_s2: a,
    })
}

/// A CDR body being read: the bytes after the encapsulation header, the read position (alignment
/// counts from 0 here), the byte order, the whole message's length (for messages).
struct Cdr<'a> {
    body: &'a [u8],
    pos: usize,
    little: bool,
    len: usize,
}

impl<'a> Cdr<'a> {
    /// `size` bytes at the next multiple of `align`.
    fn take(
        &mut self,
        size: usize,
        align: usize,
        field: &'static str,
    ) -> Result<&'a [u8], CdrError> {
        let short = CdrError::Short {
            len: self.len,
            field,
        };
        let start = self.pos.next_multiple_of(align);
        let end = start.checked_add(size).ok_or(short.clone())?;
        let b = self.body.get(start..end).ok_or(short)?;
        self.pos = end;
        Ok(b)
    }

    fn u32(&mut self, field: &'static str) -> Result<u32, CdrError> {
        let b = self.take(4, 4, field)?;
        let a = [b[0], b[1], b[2], b[3]];
        Ok(if self.little {
            u32::from_le_bytes(a)
        } else {
            u32::from_be_bytes(a)
        })
    }

    fn f64s<const N: usize>(&mut self, field: &'static str) -> Result<[f64; N], CdrError> {
        let mut out = [0.0; N];
        for v in &mut out {
            let b = self.take(8, 8, field)?;
            let a: [u8; 8] = std::array::from_fn(|k| b[k]);
            *v = if self.little {
                f64::from_le_bytes(a)
            } else {
                f64::from_be_bytes(a)
            };
        }
        Ok(out)
    }
}
