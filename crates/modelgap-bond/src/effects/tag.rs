//! Candidate ids: `<kind>:<parameter>` for changes of a parameter,
//! `<kind>@<element>` for missing elements, `calibration` (no target) for
//! the graph's own unknowns. The one place ids are written
//! ([`Tag::id`]) and read ([`Tag::read`]).

/// The kind an id names, before the graph says where it acts: deviations of
/// a parameter and factors on a modulus input share `deviation:`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Tag {
    Deviation,
    Fault,
    Viscous,
    Coulomb,
    Load,
    Inertia,
    Coupling,
    Backlash,
    Cogging,
    Brush,
    Saturation,
    FluxLimit,
    Ripple,
    Heating,
    Stiffness,
    Leak,
    Inflow,
    Overflow,
    Orifice,
    Power,
    Store,
    DeadZone,
    Gain,
    Limit,
    ActuatorLag,
    ActuatorDelay,
    ActuatorOffset,
    Lag,
    Offset,
    Drift,
    Clip,
    Scale,
    Delay,
    Declared,
    Law,
    Calibration,
}

/// Every tag with its id prefix, in menu order.
const PREFIXES: [(Tag, &str); 36] = [
    (Tag::Deviation, "deviation:"),
    (Tag::Fault, "fault:"),
    (Tag::Viscous, "viscous@"),
    (Tag::Coulomb, "coulomb@"),
    (Tag::Load, "load@"),
    (Tag::Inertia, "inertia@"),
    (Tag::Coupling, "coupling@"),
    (Tag::Backlash, "backlash@"),
    (Tag::Cogging, "cogging@"),
    (Tag::Brush, "brush@"),
    (Tag::Saturation, "saturation@"),
    (Tag::FluxLimit, "flux-limit@"),
    (Tag::Ripple, "ripple@"),
    (Tag::Heating, "heating@"),
    (Tag::Stiffness, "stiffness@"),
    (Tag::Leak, "leak@"),
    (Tag::Inflow, "inflow@"),
    (Tag::Overflow, "overflow@"),
    (Tag::Orifice, "orifice@"),
    (Tag::Power, "power@"),
    (Tag::Store, "store@"),
    (Tag::DeadZone, "deadzone@"),
    (Tag::Gain, "gain@"),
    (Tag::Limit, "limit@"),
    (Tag::ActuatorLag, "actuator-lag@"),
    (Tag::ActuatorDelay, "actuator-delay@"),
    (Tag::ActuatorOffset, "actuator-offset@"),
    (Tag::Lag, "lag@"),
    (Tag::Offset, "offset@"),
    (Tag::Drift, "drift@"),
    (Tag::Clip, "clip@"),
    (Tag::Scale, "scale@"),
    (Tag::Delay, "delay@"),
    (Tag::Declared, "declared:"),
    (Tag::Law, "law@"),
    (Tag::Calibration, "calibration"),
];

impl Tag {
    /// The id prefix (`coulomb@`).
    fn prefix(self) -> &'static str {
        PREFIXES
            .iter()
            .find(|(t, _)| *t == self)
            .map_or("", |(_, p)| p)
    }

    /// The id of this kind acting on `target` (`coulomb@1m`, `deviation:R`).
    pub(super) fn id(self, target: &str) -> String {
        format!("{}{target}", self.prefix())
    }

    /// The tag and target of an id, or `None` for an id no kind writes.
    pub(super) fn read(id: &str) -> Option<(Tag, &str)> {
        PREFIXES
            .iter()
            .find_map(|&(tag, prefix)| Some((tag, id.strip_prefix(prefix)?)))
    }

    /// The prefixes of the menu's effects, for a message listing what an id may start with:
    /// `deviation:, fault:, … or saturation@`.
    pub(super) fn expected() -> String {
        // Calibration is not a missing effect a user picks: left out.
        let all: Vec<&str> = (PREFIXES.iter())
            .filter(|(t, _)| *t != Tag::Calibration)
            .map(|(_, p)| *p)
            .collect();
        match all.split_last() {
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_read_back_to_their_tag_and_target() {
        for (tag, _) in PREFIXES {
            assert_eq!(Tag::read(&tag.id("1m")), Some((tag, "1m")));
        }
        assert_eq!(Tag::read("deviation:R"), Some((Tag::Deviation, "R")));
        assert_eq!(Tag::read("coulomb@1m"), Some((Tag::Coulomb, "1m")));
        for id in ["coulomb", "x:R", "foo@1m", ""] {
            assert_eq!(Tag::read(id), None, "{id}");
        }
    }

    #[test]
    fn the_expected_prefixes_read_as_a_list() {
        assert_eq!(
            Tag::expected(),
            "deviation:, fault:, viscous@, coulomb@, load@, inertia@, coupling@, backlash@, cogging@, brush@, saturation@, flux-limit@, ripple@, heating@, stiffness@, leak@, inflow@, overflow@, orifice@, power@, store@, deadzone@, gain@, limit@, actuator-lag@, actuator-delay@, actuator-offset@, lag@, offset@, drift@, clip@, scale@, delay@, declared: or law@"
        );
    }
}
