//! The physical domain of a 1-junction, read from the unit of its inertia.

use super::{CONTACT_SMOOTHING_A, COULOMB_SMOOTHING_M_S, COULOMB_SMOOTHING_RAD_S};

/// The physical domain of a 1-junction, from the inertia bonded to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// An electrical loop: common current, I is an inductance (H).
    Electrical,
    /// A shaft: common angular speed, I is an inertia (kg m²).
    Rotational,
    /// A moving body: common velocity, I is a mass (kg).
    Translational,
}

impl Domain {
    /// The domain a storage parameter's unit belongs to, if any (see the
    /// [module docs](super)).
    pub fn of_unit(unit: &str) -> Option<Domain> {
        let compact: String = unit
            .chars()
            .filter(|c| !matches!(c, ' ' | '*' | '·' | '.'))
            .collect();
        if matches!(compact.as_str(), "kgm^2" | "kgm²" | "kgm2") {
            return Some(Domain::Rotational);
        }
        if compact == "kg" {
            return Some(Domain::Translational);
        }
        if compact == "Wb/A" || unit.split(|c: char| !c.is_alphanumeric()).any(|t| t == "H") {
            return Some(Domain::Electrical);
        }
        None
    }

    /// True for a shaft or a moving body: where friction, loads and
    /// couplings attach.
    pub fn is_mechanical(self) -> bool {
        matches!(self, Domain::Rotational | Domain::Translational)
    }

    pub(crate) fn effort_unit(self) -> &'static str {
        match self {
            Domain::Electrical => "V",
            Domain::Rotational => "N m",
            Domain::Translational => "N",
        }
    }

    pub(crate) fn flow_unit(self) -> &'static str {
        match self {
            Domain::Electrical => "A",
            Domain::Rotational => "rad/s",
            Domain::Translational => "m/s",
        }
    }

    pub(super) fn inertia_unit(self) -> &'static str {
        match self {
            Domain::Electrical => "H",
            Domain::Rotational => "kg m^2",
            Domain::Translational => "kg",
        }
    }

    pub(super) fn damping_unit(self) -> &'static str {
        match self {
            Domain::Electrical => "Ohm",
            Domain::Rotational => "N m s/rad",
            Domain::Translational => "N s/m",
        }
    }

    pub(super) fn stiffness_unit(self) -> &'static str {
        match self {
            Domain::Electrical => "1/F",
            Domain::Rotational => "N m/rad",
            Domain::Translational => "N/m",
        }
    }

    pub(super) fn effort_word(self) -> &'static str {
        match self {
            Domain::Electrical => "voltage",
            Domain::Rotational => "torque",
            Domain::Translational => "force",
        }
    }

    pub(super) fn inertia_word(self) -> &'static str {
        match self {
            Domain::Electrical => "inductance",
            Domain::Rotational => "inertia",
            Domain::Translational => "mass",
        }
    }

    /// Parameter-name stems: (effort strength, inertia increment, second inertia).
    pub(super) fn stems(self) -> (&'static str, &'static str, &'static str) {
        match self {
            Domain::Rotational => ("tau", "dJ", "J2"),
            Domain::Translational => ("F", "dm", "m2"),
            Domain::Electrical => ("v", "dL", "L2"),
        }
    }

    /// The fixed smoothing flow of a Coulomb friction or a contact drop.
    pub(super) fn coulomb_smoothing(self) -> f64 {
        match self {
            Domain::Rotational => COULOMB_SMOOTHING_RAD_S,
            Domain::Translational => COULOMB_SMOOTHING_M_S,
            Domain::Electrical => CONTACT_SMOOTHING_A,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn storage_units_give_the_junction_domain() {
        for (unit, domain) in [
            ("H", Some(Domain::Electrical)),
            ("Wb/A", Some(Domain::Electrical)),
            ("kg m^2", Some(Domain::Rotational)),
            ("kg*m^2", Some(Domain::Rotational)),
            ("kg·m²", Some(Domain::Rotational)),
            ("kg", Some(Domain::Translational)),
            ("Hz", None),
            ("N m/A", None),
            ("", None),
        ] {
            assert_eq!(Domain::of_unit(unit), domain, "{unit}");
        }
    }
}
