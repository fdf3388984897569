//! Real-time scheduling for the polling thread: `SCHED_FIFO` at a configured priority
//! (`bus.realtime_priority`), when the system permits it (root, `CAP_SYS_NICE` or an
//! `RLIMIT_RTPRIO` allowance); otherwise the thread keeps normal scheduling.
//!
//! A `SCHED_FIFO` thread preempts every normal thread the moment its sleep ends, so a busy
//! machine no longer delays its wake-ups by a scheduler time slice. The polling thread sleeps
//! most of each period, so it cannot starve the rest of the system.

/// Asks for `SCHED_FIFO` at `priority` (1..=99) for the calling thread. `Err` says why not
/// (the thread's scheduling is then unchanged).
#[cfg(target_os = "linux")]
pub fn request_fifo(priority: u8) -> Result<(), String> {
    if !(1..=99).contains(&priority) {
        return Err(format!("priority {priority} is outside 1..=99"));
    }
    // musl's sched_param has more fields (the sporadic server's) than glibc's: start from
    // zero and set the one that SCHED_FIFO reads.
    // SAFETY: sched_param is plain integers (and timespecs of integers); all zero is valid.
    let mut param: libc::sched_param = unsafe { std::mem::zeroed() };
    param.sched_priority = i32::from(priority);
    // SAFETY: `param` is a valid sched_param that lives across the call; pid 0 is the
    // calling thread.
    let result = unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) };
    if result == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error().to_string())
    }
}

/// Sets the calling thread's timer slack to 1 ns. Linux lets a normal thread's sleep end up
/// to 50 us after its deadline (the default slack, which batches wake-ups); the polling
/// thread wants its deadline. (A `SCHED_FIFO` thread has no slack anyway.) Returns whether
/// the kernel took it.
#[cfg(target_os = "linux")]
pub fn minimize_timer_slack() -> bool {
    // SAFETY: PR_SET_TIMERSLACK takes one unsigned long argument and touches no memory.
    unsafe { libc::prctl(libc::PR_SET_TIMERSLACK, 1 as libc::c_ulong) == 0 }
}

/// Timer slack is a Linux notion: nothing to do here.
#[cfg(not(target_os = "linux"))]
pub fn minimize_timer_slack() -> bool {
    false
}

/// Asks for `SCHED_FIFO`: not available on this platform.
#[cfg(not(target_os = "linux"))]
pub fn request_fifo(priority: u8) -> Result<(), String> {
    Err(format!(
        "SCHED_FIFO (priority {priority}) is only requested on Linux"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_priorities_are_refused_before_asking() {
        assert!(request_fifo(0).unwrap_err().contains("outside 1..=99"));
        assert!(request_fifo(100).unwrap_err().contains("outside 1..=99"));
    }
}
