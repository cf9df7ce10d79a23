//! The share of the machine's processor time its hypervisor took while a benchmark ran.
//!
//! On a virtual machine whose host is shared, the hypervisor runs other guests on the cores
//! this one was given ("steal" time). A benchmark then slows down for reasons that are not in
//! the code, by tens of percent from one run to the next, and threads that wait for each other
//! suffer most. `clothsim bench` prints the share next to each timing, so a reader knows which
//! figures to trust.

use std::path::Path;

/// Cumulative processor time of all cores, in the kernel's ticks: the `cpu` line of
/// `/proc/stat`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CpuTimes {
    /// Every state's ticks summed (user, nice, system, idle, iowait, irq, softirq, steal).
    total: u64,
    /// The ticks stolen by the hypervisor.
    steal: u64,
}

impl CpuTimes {
    /// The machine's times now, or `None` where the kernel does not give them (not Linux, or no
    /// `/proc`).
    pub fn now() -> Option<Self> {
        Self::read(Path::new("/proc/stat"))
    }

    fn read(path: &Path) -> Option<Self> {
        let text = std::fs::read_to_string(path).ok()?;
        Self::parse(&text)
    }

    /// The times of `/proc/stat`'s text: its aggregate `cpu` line, whose fields are user, nice,
    /// system, idle, iowait, irq, softirq, steal, guest and guest_nice ticks. Guest time is
    /// already counted in user and nice, so it is left out of the total. Kernels before 2.6.11
    /// have no steal field: `None`.
    pub fn parse(text: &str) -> Option<Self> {
        let line = text
            .lines()
            .find(|l| l.split_whitespace().next() == Some("cpu"))?;
        let fields: Vec<u64> = line
            .split_whitespace()
            .skip(1)
            .map(str::parse)
            .collect::<Result<_, _>>()
            .ok()?;
        let states = fields.get(..8)?;
        Some(Self {
            total: states.iter().sum(),
            steal: states[7],
        })
    }

    /// The percentage of all processor time from `self` to `later` that was stolen, or `None`
    /// when no tick passed (or the counters went back).
    pub fn steal_percent_until(self, later: Self) -> Option<f64> {
        let total = later.total.checked_sub(self.total)?;
        let steal = later.steal.checked_sub(self.steal)?;
        (total > 0).then(|| 100.0 * steal as f64 / total as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `/proc/stat` head as Linux 6 prints it.
    const STAT: &str = "cpu  1779755 0 71647 7257503 3331 0 1253 157832 0 0\n\
                        cpu0 889000 0 35000 3628000 1600 0 600 79000 0 0\n\
                        intr 12345 0 0\n";

    #[test]
    fn reads_the_aggregate_line_not_a_cores() {
        let t = CpuTimes::parse(STAT).unwrap();
        assert_eq!(t.steal, 157_832);
        assert_eq!(
            t.total,
            1_779_755 + 71_647 + 7_257_503 + 3_331 + 1_253 + 157_832
        );
    }

    #[test]
    fn the_share_is_the_stolen_ticks_over_all_ticks_between_readings() {
        let before = CpuTimes {
            total: 1_000,
            steal: 100,
        };
        let after = CpuTimes {
            total: 1_400,
            steal: 200,
        };
        assert_eq!(before.steal_percent_until(after), Some(25.0));
        // No tick passed, or the counters went back (another boot): no figure.
        assert_eq!(before.steal_percent_until(before), None);
        assert_eq!(after.steal_percent_until(before), None);
    }

    #[test]
    fn text_without_a_steal_field_or_with_junk_gives_no_times() {
        // Before Linux 2.6.11 the line had seven fields.
        assert_eq!(CpuTimes::parse("cpu 1 2 3 4 5 6 7\n"), None);
        assert_eq!(CpuTimes::parse("cpu 1 2 x 4 5 6 7 8\n"), None);
        assert_eq!(CpuTimes::parse("intr 1 2 3\n"), None);
        assert_eq!(CpuTimes::parse(""), None);
    }

    #[test]
    fn this_machine_gives_times_or_none_but_never_fails() {
        // On Linux `/proc/stat` is there and readable; elsewhere the figure is simply absent.
        let now = CpuTimes::now();
        if cfg!(target_os = "linux") {
            assert!(now.is_some(), "/proc/stat unreadable on Linux");
        }
        assert_eq!(CpuTimes::read(Path::new("/nonexistent/stat")), None);
    }
}
