//! Built-in models, shipped as model files.

use crate::error::{BondError, Result};
use crate::file::read_model;
use crate::graph::BondGraph;

/// The DC motor of the paper's Fig. 3 (bonds 1..8 as in the paper).
pub const DC_MOTOR_TOML: &str = include_str!("../../models/dc-motor.toml");
/// The buck converter feeding the DC motor (the paper's section 5).
pub const BUCK_MOTOR_TOML: &str = include_str!("../../models/buck-motor.toml");

/// Names of the built-in models, with their file text.
pub const BUILTINS: [(&str, &str); 2] =
    [("dc-motor", DC_MOTOR_TOML), ("buck-motor", BUCK_MOTOR_TOML)];

/// The DC motor: R = 1 Ω, L = 5 mH, k = 0.05 N·m/A, J = 1e-4 kg·m²,
/// β = 1e-5 N·m·s/rad; inputs `V` (12 V) and `tau_L` (0); outputs `i`, `omega`.
pub fn dc_motor() -> BondGraph {
    builtin("dc-motor").unwrap_or_default()
}

/// The buck converter (switch as MTF `m`) feeding the DC motor; inputs `Vs`
/// (24 V), `m` (0.5: averaged duty cycle, or a PWM signal), `tau_L`;
/// outputs `i`, `omega`, `v_c`.
pub fn buck_motor() -> BondGraph {
    builtin("buck-motor").unwrap_or_default()
}

/// A built-in model by name (`dc-motor`, `buck-motor`; `_` may stand for `-`).
///
/// # Errors
/// [`BondError::UnknownModel`] listing the built-ins.
pub fn builtin(name: &str) -> Result<BondGraph> {
    let wanted = name.replace('_', "-");
    for (n, src) in BUILTINS {
        if n == wanted {
            return read_model(src);
        }
    }
    Err(BondError::UnknownModel {
        name: name.to_string(),
        known: BUILTINS
            .iter()
            .map(|(n, _)| *n)
            .collect::<Vec<_>>()
            .join(", "),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_parse_and_validate() {
        for (name, _) in BUILTINS {
            let g = builtin(name).unwrap();
            g.validate().unwrap();
        }
    }
}
