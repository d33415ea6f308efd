//! The reader streams: its peak heap use does not grow with the number of rows. Measured with a
//! counting global allocator (this test binary only) while reading rows generated on the fly; the
//! tests take [`LOCK`] so that one's allocations do not count in the other's peak.

use recording::session::{read_samples, Plan};
use std::alloc::{GlobalAlloc, Layout, System};
use std::io::{BufReader, Read};
use std::path::Path;
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

/// One measurement at a time.
static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Peak heap growth while `f` runs, bytes.
fn peak_during<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let base = CURRENT.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let out = f();
    (out, PEAK.load(Ordering::Relaxed).saturating_sub(base))
}

/// `samples.csv` text of `rows` rows, produced as it is read.
struct Rows {
    left: u64,
    k: u64,
    pending: Vec<u8>,
    at: usize,
}

impl Read for Rows {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.at == self.pending.len() {
            self.pending.clear();
            self.at = 0;
            if self.k == 0 {
                self.pending
                    .extend_from_slice(b"segment,t_s,u_x,u_y,u_z,w_x,w_y,w_z\n");
            }
            while self.left > 0 && self.pending.len() < 4096 {
                let t = self.k as f64 * 1e-3;
                let x = (self.k as f64 * 0.37).sin();
                let line = format!(
                    "x+,{t},{},{},{},{},{},{}\n",
                    2.4 + 1e-3 * x,
                    2.38,
                    2.43 - 1e-3 * x,
                    1e-3 * x,
                    0.0,
                    -1e-3
                );
                self.pending.extend_from_slice(line.as_bytes());
                self.left -= 1;
                self.k += 1;
            }
        }
        let n = buf.len().min(self.pending.len() - self.at);
        buf[..n].copy_from_slice(&self.pending[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

fn peak_while_reading(rows: u64, plan: &Plan) -> usize {
    let reader = BufReader::with_capacity(
        1 << 16,
        Rows {
            left: rows,
            k: 0,
            pending: Vec::with_capacity(8192),
            at: 0,
        },
    );
    let ((stats, report), peak) =
        peak_during(|| read_samples(reader, plan, Path::new("generated")).unwrap());
    assert_eq!((stats[0].count, report.rows), (rows, rows));
    peak
}

#[test]
fn peak_memory_does_not_grow_with_rows() {
    let _one_at_a_time = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let plan = Plan::parse(
        "output_unit = \"V\"\nsample_rate_hz = 1000\n[[segment]]\nname = \"x+\"\nup_b = [1, 0, 0]\n",
    )
    .unwrap();
    let small = peak_while_reading(20_000, &plan);
    let large = peak_while_reading(200_000, &plan);
    eprintln!("peak heap while reading: {small} bytes for 20 000 rows, {large} for 200 000");
    // 10× the rows (~10 MB of text): the same working set, well under the text's size.
    assert!(large < 512 * 1024, "peak {large} bytes");
    assert!(large <= small + 16 * 1024, "{small} → {large} bytes");
}

#[test]
fn noise_refuses_an_endless_line_with_bounded_memory() {
    let _one_at_a_time = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    // 300 MB without a line end (a sparse file: zeros, instant to make), then an endless one.
    let dir = tempfile::tempdir().unwrap();
    let flat = dir.path().join("no-line-end.csv");
    std::fs::File::create(&flat)
        .unwrap()
        .set_len(300_000_000)
        .unwrap();
    for input in [flat.as_path(), Path::new("/dev/zero")] {
        let read_before = bytes_read_by_this_process();
        let (result, peak) = peak_during(|| {
            outputs::noise::analyse(input, None, recording::testkit::SPELLING, true)
        });
        let read = bytes_read_by_this_process() - read_before;
        let e = result.unwrap_err().to_string();
        eprintln!(
            "noise --input {}: peak heap {peak} bytes, {read} bytes read: {e}",
            input.display(),
        );
        assert!(e.contains("line 1 is longer than 4096 bytes"), "{e}");
        // The 1 MB read buffer and one bounded line, not the file.
        assert!(peak < 4 << 20, "peak {peak} bytes");
        // Refused at its first line: a few buffers read, not the 300 MB (counted by the kernel, so
        // a loaded machine cannot make it fail as a time limit could).
        assert!(read < 8 << 20, "{read} bytes read");
    }
}

/// Bytes this process has read through `read` system calls so far (`rchar` of `/proc/self/io`).
/// The tests here hold [`LOCK`], so no other test of this file reads while one measures.
fn bytes_read_by_this_process() -> u64 {
    let io = std::fs::read_to_string("/proc/self/io").unwrap();
    io.lines()
        .find_map(|l| l.strip_prefix("rchar: "))
        .and_then(|v| v.trim().parse().ok())
        .unwrap()
}
