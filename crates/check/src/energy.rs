//! The cloth's total energy and its parts, J: the measure the divergence guard judges runs by
//! too, so the kit's energy figures and a run's stop agree.

pub(crate) use cloth_solver::energy::{kinetic, scale, spring, total};
