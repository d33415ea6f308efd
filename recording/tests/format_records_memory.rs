//! A binary log's format records cost memory bounded by their count and size, not by how many of
//! them a file holds: a ULog of many oversized format definitions (each up to its 65 535-byte
//! message, some 16 000 fields) is read within a few MB, and its IMU is still read. Measured with
//! a counting global allocator (this test binary only).

use recording::session::logs::ulog;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let now = CURRENT.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
        PEAK.fetch_max(now, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

/// Peak heap growth while `f` runs, bytes.
fn peak_during<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let base = CURRENT.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let out = f();
    (out, PEAK.load(Ordering::Relaxed).saturating_sub(base))
}

/// A ULog of `junk` format definitions of about 64 KB each (16 000 one-letter fields, or one
/// field of a 64 KB name when `long_names`), then the IMU's topics and 1000 samples of each at
/// 1 kHz.
fn oversized_definitions(junk: usize, long_names: bool) -> Vec<u8> {
    const IMU: &str = "uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;\
        float y;float z;float temperature;";
    let mut out = ulog::MAGIC.to_vec();
    out.push(1);
    out.extend(0u64.to_le_bytes());
    let mut msg = |ty: u8, body: &[u8]| {
        out.extend((body.len() as u16).to_le_bytes());
        out.push(ty);
        out.extend_from_slice(body);
    };
    for k in 0..junk {
        let mut def = format!("junk{k}:");
        if long_names {
            def.push_str("uint8_t ");
        }
        while def.len() + 4 <= u16::MAX as usize {
            def.push_str(if long_names { "aaaa" } else { "x a;" });
        }
        msg(b'F', def.as_bytes());
    }
    for name in ["sensor_accel", "sensor_gyro"] {
        msg(b'F', format!("{name}:{IMU}").as_bytes());
    }
    for (id, name) in ["sensor_accel", "sensor_gyro"].iter().enumerate() {
        let mut b = vec![0u8];
        b.extend((id as u16).to_le_bytes());
        b.extend(name.as_bytes());
        msg(b'A', &b);
    }
    for k in 0..1000u64 {
        for id in 0..2u16 {
            let mut b = id.to_le_bytes().to_vec();
            let us = 1_000_000 + k * 1000;
            b.extend(us.to_le_bytes());
            b.extend(us.to_le_bytes());
            b.extend(7u32.to_le_bytes());
            let v: [f32; 4] = if id == 0 {
                [0.0, 0.0, -9.81, 30.0]
            } else {
                [0.0; 4]
            };
            v.iter().for_each(|x| b.extend(x.to_le_bytes()));
            msg(b'D', &b);
        }
    }
    out
}

#[test]
fn many_oversized_ulog_format_definitions_cost_bounded_memory() {
    // Unbounded, each definition of 16 000 fields costs about 1 MB: 128 MB for 128 of them; each
    // of one long name, its 64 KB: 16 MB for 256.
    for (junk, long_names) in [(128, false), (256, true)] {
        let bytes = oversized_definitions(junk, long_names);
        let ((rec, warnings), peak) =
            peak_during(|| ulog::read(std::io::Cursor::new(&bytes), 0).expect("the IMU is read"));
        println!(
            "{} bytes of {junk} definitions: peak heap {peak} bytes; {warnings:?}",
            bytes.len()
        );
        assert_eq!(rec.t_s.len(), 1000);
        assert!(
            warnings
                .iter()
                .any(|w| w.to_string().contains("format definition(s) beyond")),
            "{warnings:?}"
        );
        assert!(peak < 10 << 20, "peak heap {peak} bytes");
    }
}
