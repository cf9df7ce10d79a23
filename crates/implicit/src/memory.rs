//! Fallible allocation of the implicit solvers' large buffers, so that a cloth too large for the
//! machine is an error value instead of an aborted process.
//!
//! Whether the machine has the memory is not asked here: each solver's registry entry states
//! what it needs (`memory_estimate`, from the same symbolic analysis the solver allocates by),
//! and the application checks that against the memory available before it builds a solver.
//! What is left to this module is an allocation the system refuses outright.

use std::fmt;

/// A buffer that could not be allocated: what it was for and how large it was.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Allocation {
    /// What the buffer holds.
    pub(crate) what: &'static str,
    /// Its size, bytes.
    pub(crate) bytes: u64,
}

impl fmt::Display for Allocation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "cannot allocate {:.1} MiB for {}: the cloth is too large for this machine's memory \
             (use a smaller grid, or the verlet solver, which needs no matrix)",
            self.bytes as f64 / f64::from(1 << 20),
            self.what
        )
    }
}

/// A vector of `len` copies of `value`, or the [`Allocation`] that failed.
pub(crate) fn try_filled<T: Clone>(
    len: usize,
    value: T,
    what: &'static str,
) -> Result<Vec<T>, Allocation> {
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| Allocation {
        what,
        bytes: (len as u64).saturating_mul(std::mem::size_of::<T>() as u64),
    })?;
    v.resize(len, value);
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_impossible_allocation_is_an_error_naming_its_size() {
        let e = try_filled(usize::MAX / 8, 0.0_f64, "a test buffer").unwrap_err();
        assert_eq!(e.what, "a test buffer");
        assert!(e.to_string().contains("a test buffer"), "{e}");
        assert!(e.to_string().contains("MiB"), "{e}");
    }
}
