//! What this process has used so far: peak resident memory and CPU time, from Linux's `/proc`
//! (`None` elsewhere), for run summaries and `polyphase bench coupled`.

use std::fs;

/// Clock ticks per second of the times in `/proc/self/stat` (USER_HZ, fixed at 100 in the
/// Linux user-space ABI whatever the kernel's own tick rate).
const USER_HZ: f64 = 100.0;

/// Peak resident set size in bytes (`VmHWM` of `/proc/self/status`).
pub fn peak_rss_bytes() -> Option<u64> {
    let status = fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// User plus system CPU seconds of every thread (fields 14 and 15 of `/proc/self/stat`).
pub fn cpu_seconds() -> Option<f64> {
    let stat = fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) may hold spaces; the fields after its closing ')' do not.
    let rest = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // `rest` starts at field 3 (state), so field n is at index n − 3.
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    Some((utime + stime) / USER_HZ)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_time_grows_with_work_and_memory_is_read() {
        let before = cpu_seconds().expect("Linux /proc");
        let mut x = 0u64;
        let start = std::time::Instant::now();
        while start.elapsed().as_secs_f64() < 0.3 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
        }
        std::hint::black_box(x);
        let after = cpu_seconds().expect("Linux /proc");
        // 0.3 s of busy loop on this thread: at least 0.1 s even if a loaded machine gives it
        // only half the wall time and both readings round down by a 10 ms tick.
        assert!(after - before >= 0.1, "{before} → {after}");
        // A test binary holds at least a megabyte resident.
        assert!(peak_rss_bytes().expect("Linux /proc") > 1 << 20);
    }
}
