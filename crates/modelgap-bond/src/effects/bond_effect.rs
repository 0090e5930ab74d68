//! [`BondEffect`]: the enum over the kinds of effect, and the one place a
//! candidate's id is read ([`BondEffect::from_candidate`]).

use modelgap_core::{Candidate, EffectKind};

use super::def::{EffectDef, QualTarget};
use super::edit::bad;
use super::scales::Scales;
use super::tag::Tag;
use super::{
    ActuatorDelay, ActuatorGain, ActuatorLag, ActuatorLimit, ActuatorOffset, Backlash, Brush,
    Calibration, Cogging, Coulomb, Coupling, DeadZone, Declared, Deviation, Factor, Fault, Faulted,
    FluxLimit, Heating, Inertia, Inflow, Junction, LawEffect, Leak, Load, ModulusRipple, Node,
    Orifice, Overflow, PowerLoss, Saturation, SensorClip, SensorDelay, SensorDrift, SensorLag,
    SensorOffset, SensorScale, Stiffness, Store, Viscous,
};
use crate::error::{BondError, Result};
use crate::graph::{BondGraph, ElementId};
use crate::simulate::ParamChange;

/// A candidate effect of a bond graph, typed: its kind and where it acts.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BondEffect {
    /// `deviation:<p>`: a parameter is off.
    Deviation(Deviation),
    /// `deviation:<u>`: a modulus input is off by a factor.
    Factor(Factor),
    /// `fault:<p>`, `fault:<u>`: an abrupt change at an unknown time.
    Fault(Fault),
    /// `viscous@<j>`: viscous friction.
    Viscous(Viscous),
    /// `coulomb@<j>`: Coulomb friction.
    Coulomb(Coulomb),
    /// `load@<j>`: a constant load.
    Load(Load),
    /// `inertia@<j>`: extra inertia.
    Inertia(Inertia),
    /// `coupling@<j>`: a flexible coupling to a second inertia.
    Coupling(Coupling),
    /// `backlash@<j>`: part of the inertia behind a gap.
    Backlash(Backlash),
    /// `cogging@<j>`: cogging torque.
    Cogging(Cogging),
    /// `brush@<j>`: a brush/contact voltage drop.
    Brush(Brush),
    /// `saturation@<I>`: magnetic saturation.
    Saturation(Saturation),
    /// `flux-limit@<I>`: magnetic saturation towards a limiting flux.
    FluxLimit(FluxLimit),
    /// `ripple@<GY>`: a motor constant that varies around a turn.
    Ripple(ModulusRipple),
    /// `heating@<R>`: a resistance that rises with the energy it dissipates.
    Heating(Heating),
    /// `stiffness@<C>`: a cubic term in a C's law.
    Stiffness(Stiffness),
    /// `leak@<node>`: a linear loss from a storage node.
    Leak(Leak),
    /// `inflow@<node>`: a constant flow into a storage node.
    Inflow(Inflow),
    /// `overflow@<node>`: outflow above a threshold.
    Overflow(Overflow),
    /// `orifice@<node>`: turbulent outflow through an orifice (√ of the effort).
    Orifice(Orifice),
    /// `power@<node>`: a loss growing as a power of a thermal node's temperature.
    Power(PowerLoss),
    /// `store@<node>`: a second storage behind a resistance.
    Store(Store),
    /// `deadzone@<source>`: a dead zone in what a driven source imposes.
    DeadZone(DeadZone),
    /// `gain@<source>`: a gain on what a driven source imposes.
    Gain(ActuatorGain),
    /// `actuator-offset@<source>`: a constant added to what a driven source imposes.
    ActuatorOffset(ActuatorOffset),
    /// `limit@<source>`: a driven source that saturates.
    Limit(ActuatorLimit),
    /// `actuator-lag@<source>`: a driven source follows its command through a lag.
    ActuatorLag(ActuatorLag),
    /// `actuator-delay@<source>`: a driven source follows its command a delay behind.
    ActuatorDelay(ActuatorDelay),
    /// `lag@<output>`: a first-order lag in an output's sensor.
    Lag(SensorLag),
    /// `offset@<output>`: a constant offset in an output's sensor.
    Offset(SensorOffset),
    /// `drift@<output>`: a sensor whose zero drifts at a steady rate.
    Drift(SensorDrift),
    /// `clip@<output>`: a sensor that reads nothing beyond its range.
    Clip(SensorClip),
    /// `scale@<output>`: a gain in an output's sensor.
    Scale(SensorScale),
    /// `delay@<output>`: a pure delay in an output's sensor.
    Delay(SensorDelay),
    /// `declared:<name>`: an effect the model file declares.
    Declared(Declared),
    /// `law@<place>:<formula>`: a law discovery found (never on the menu).
    Law(LawEffect),
    /// `calibration`: the graph's free parameters and initial states (never
    /// on the menu; see [`Calibration`]).
    Calibration(Calibration),
}

macro_rules! from_kind {
    ($($kind:ident),*) => {$(
        impl From<$kind> for BondEffect {
            fn from(k: $kind) -> BondEffect {
                BondEffect::$kind(k)
            }
        }
    )*};
}
from_kind!(
    Deviation,
    Factor,
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
    Heating,
    Stiffness,
    Leak,
    Inflow,
    Overflow,
    Orifice,
    Store,
    DeadZone,
    ActuatorLag,
    ActuatorDelay,
    ActuatorOffset,
    Declared,
    Calibration
);

impl From<ModulusRipple> for BondEffect {
    fn from(k: ModulusRipple) -> BondEffect {
        BondEffect::Ripple(k)
    }
}

impl From<PowerLoss> for BondEffect {
    fn from(k: PowerLoss) -> BondEffect {
        BondEffect::Power(k)
    }
}

impl From<ActuatorGain> for BondEffect {
    fn from(k: ActuatorGain) -> BondEffect {
        BondEffect::Gain(k)
    }
}

impl From<ActuatorLimit> for BondEffect {
    fn from(k: ActuatorLimit) -> BondEffect {
        BondEffect::Limit(k)
    }
}

impl From<SensorClip> for BondEffect {
    fn from(k: SensorClip) -> BondEffect {
        BondEffect::Clip(k)
    }
}

impl From<SensorOffset> for BondEffect {
    fn from(k: SensorOffset) -> BondEffect {
        BondEffect::Offset(k)
    }
}

impl From<SensorDrift> for BondEffect {
    fn from(k: SensorDrift) -> BondEffect {
        BondEffect::Drift(k)
    }
}

impl From<SensorScale> for BondEffect {
    fn from(k: SensorScale) -> BondEffect {
        BondEffect::Scale(k)
    }
}

impl From<SensorDelay> for BondEffect {
    fn from(k: SensorDelay) -> BondEffect {
        BondEffect::Delay(k)
    }
}

impl From<SensorLag> for BondEffect {
    fn from(k: SensorLag) -> BondEffect {
        BondEffect::Lag(k)
    }
}

impl BondEffect {
    /// Reads a candidate of `g`: its id names the kind and where it acts
    /// (a parameter or input after `:`, an element after `@`). The only
    /// place the bond crate reads a candidate's id.
    ///
    /// # Errors
    /// [`BondError::BadEffect`] naming the candidate for an id no kind
    /// writes, or one `g` cannot take: an unknown parameter, modulus input,
    /// junction or I element, or a junction of the wrong domain.
    ///
    /// # Example
    /// ```
    /// # use modelgap_bond::effects::{self, BondEffect};
    /// # use modelgap_bond::library;
    /// let motor = library::dc_motor();
    /// let menu = effects::candidates(&motor);
    /// let coulomb = menu.iter().find(|c| c.id == "coulomb@1m").unwrap();
    /// let effect = BondEffect::from_candidate(coulomb, &motor).unwrap();
    /// assert!(matches!(effect, BondEffect::Coulomb(_)));
    /// ```
    pub fn from_candidate(c: &Candidate, g: &BondGraph) -> Result<BondEffect> {
        let (tag, target) = Tag::read(&c.id).ok_or_else(|| unknown(c))?;
        let steady = || -> Result<Faulted> {
            if let Some(d) = Deviation::at(g, target) {
                Ok(Faulted::Parameter(d))
            } else if let Some(f) = Factor::at(g, target) {
                Ok(Faulted::Modulus(f))
            } else {
                Err(bad(
                    c,
                    "",
                    format!("the model has no parameter or modulus input '{target}'"),
                ))
            }
        };
        let junction = || -> Result<Junction> {
            let id = g.find(target).ok_or_else(|| {
                bad(
                    c,
                    "",
                    format!("the model has no junction '{target}' for this effect"),
                )
            })?;
            Junction::of(g, id).ok_or_else(|| {
                bad(
                    c,
                    "",
                    format!("'{target}' is not a 1-junction with an inertia (I) of known unit"),
                )
            })
        };
        let node = || -> Result<Node> {
            g.find(target)
                .and_then(|id| Node::of(g, id))
                .ok_or_else(|| {
                    bad(
                        c,
                        "",
                        format!("'{target}' is not a 0-junction with a C (a storage node)"),
                    )
                })
        };
        // A source an input drives: where every actuator effect acts.
        let source = || -> Result<ElementId> {
            g.find(target)
                .filter(|&id| DeadZone::at(g, id).is_some())
                .ok_or_else(|| {
                    bad(
                        c,
                        "",
                        format!("the model has no source '{target}' driven by an input"),
                    )
                })
        };
        let effect = match tag {
            Tag::Deviation => match steady()? {
                Faulted::Parameter(d) => Some(BondEffect::Deviation(d)),
                Faulted::Modulus(f) => Some(BondEffect::Factor(f)),
            },
            Tag::Fault => Some(BondEffect::Fault(Fault { of: steady()? })),
            Tag::Saturation => {
                let s = g.find(target).and_then(|id| Saturation::at(g, id));
                let s =
                    s.ok_or_else(|| bad(c, "", format!("the model has no I element '{target}'")))?;
                Some(BondEffect::Saturation(s))
            }
            Tag::FluxLimit => {
                let s = g.find(target).and_then(|id| FluxLimit::at(g, id));
                let s =
                    s.ok_or_else(|| bad(c, "", format!("the model has no I element '{target}'")))?;
                Some(BondEffect::FluxLimit(s))
            }
            Tag::Ripple => {
                let r = g.find(target).and_then(|id| ModulusRipple::at(g, id));
                let r = r.ok_or_else(|| {
                    bad(
                        c,
                        "",
                        format!(
                            "'{target}' is not a GY of the model with a linear modulus bonded to a rotational 1-junction"
                        ),
                    )
                })?;
                Some(BondEffect::Ripple(r))
            }
            Tag::Heating => {
                let h = g.find(target).and_then(|id| Heating::at(g, id));
                let h = h.ok_or_else(|| {
                    bad(
                        c,
                        "",
                        format!(
                            "'{target}' is not an R of the model with a linear resistance on an electrical 1-junction"
                        ),
                    )
                })?;
                Some(BondEffect::Heating(h))
            }
            Tag::Stiffness => {
                let s = g.find(target).and_then(|id| Stiffness::at(g, id));
                let s = s.ok_or_else(|| {
                    bad(
                        c,
                        "",
                        format!("the model has no C element '{target}' with an effort law"),
                    )
                })?;
                Some(BondEffect::Stiffness(s))
            }
            Tag::Leak => Some(BondEffect::Leak(Leak { node: node()? })),
            Tag::Inflow => Some(BondEffect::Inflow(Inflow { node: node()? })),
            Tag::Overflow => Some(BondEffect::Overflow(Overflow { node: node()? })),
            Tag::Orifice => Some(BondEffect::Orifice(Orifice::at(node()?).ok_or_else(
                || {
                    bad(
                        c,
                        "",
                        format!("'{target}' is not a hydraulic or pneumatic node"),
                    )
                },
            )?)),
            Tag::Power => Some(BondEffect::Power(
                PowerLoss::at(node()?)
                    .ok_or_else(|| bad(c, "", format!("'{target}' is not a thermal node")))?,
            )),
            Tag::Store => Some(BondEffect::Store(Store { node: node()? })),
            Tag::DeadZone => Some(BondEffect::DeadZone(DeadZone { source: source()? })),
            Tag::Gain => Some(BondEffect::Gain(ActuatorGain { source: source()? })),
            Tag::ActuatorOffset => Some(BondEffect::ActuatorOffset(ActuatorOffset {
                source: source()?,
            })),
            Tag::Limit => Some(BondEffect::Limit(ActuatorLimit { source: source()? })),
            Tag::ActuatorLag => Some(BondEffect::ActuatorLag(ActuatorLag { source: source()? })),
            Tag::ActuatorDelay => Some(BondEffect::ActuatorDelay(ActuatorDelay {
                source: source()?,
            })),
            Tag::Lag => {
                let l = SensorLag::named(g, target).ok_or_else(|| {
                    bad(
                        c,
                        "",
                        format!("the model has no output '{target}' a lag can follow"),
                    )
                })?;
                Some(BondEffect::Lag(l))
            }
            Tag::Offset => {
                let o = SensorOffset::named(g, target).ok_or_else(|| {
                    bad(
                        c,
                        "",
                        format!("the model has no output '{target}' an offset can shift"),
                    )
                })?;
                Some(BondEffect::Offset(o))
            }
            Tag::Drift => {
                let o = SensorDrift::named(g, target).ok_or_else(|| {
                    bad(
                        c,
                        "",
                        format!("the model has no output '{target}' a drift can move"),
                    )
                })?;
                Some(BondEffect::Drift(o))
            }
            Tag::Clip => {
                let o = SensorClip::named(g, target).ok_or_else(|| {
                    bad(
                        c,
                        "",
                        format!("the model has no output '{target}' a sensor range can clip"),
                    )
                })?;
                Some(BondEffect::Clip(o))
            }
            Tag::Scale => {
                let o = SensorScale::named(g, target).ok_or_else(|| {
                    bad(
                        c,
                        "",
                        format!("the model has no output '{target}' a sensor gain can scale"),
                    )
                })?;
                Some(BondEffect::Scale(o))
            }
            Tag::Delay => {
                let o = SensorDelay::named(g, target).ok_or_else(|| {
                    bad(
                        c,
                        "",
                        format!("the model has no output '{target}' a delay can hold back"),
                    )
                })?;
                Some(BondEffect::Delay(o))
            }
            Tag::Declared => Some(BondEffect::Declared(
                Declared::named(g, target).ok_or_else(|| {
                    bad(c, "", format!("the model declares no candidate '{target}'"))
                })?,
            )),
            Tag::Viscous => Viscous::at(junction()?).map(Into::into),
            Tag::Coulomb => Coulomb::at(junction()?).map(Into::into),
            Tag::Load => Load::at(junction()?).map(Into::into),
            Tag::Inertia => Inertia::at(junction()?).map(Into::into),
            Tag::Coupling => Coupling::at(junction()?).map(Into::into),
            Tag::Backlash => Backlash::at(junction()?).map(Into::into),
            Tag::Cogging => Cogging::at(junction()?).map(Into::into),
            Tag::Brush => Brush::at(junction()?).map(Into::into),
            Tag::Law => Some(BondEffect::Law(LawEffect::read(g, target).ok_or_else(
                || {
                    bad(
                        c,
                        "",
                        format!(
                            "'{target}' is not a junction of the model followed by ':' and a law"
                        ),
                    )
                },
            )?)),
            Tag::Calibration => target
                .is_empty()
                .then_some(BondEffect::Calibration(Calibration)),
        };
        effect.ok_or_else(|| unknown(c))
    }

    /// The kind's definition.
    pub fn def(&self) -> &dyn EffectDef {
        match self {
            BondEffect::Deviation(k) => k,
            BondEffect::Factor(k) => k,
            BondEffect::Fault(k) => k,
            BondEffect::Viscous(k) => k,
            BondEffect::Coulomb(k) => k,
            BondEffect::Load(k) => k,
            BondEffect::Inertia(k) => k,
            BondEffect::Coupling(k) => k,
            BondEffect::Backlash(k) => k,
            BondEffect::Cogging(k) => k,
            BondEffect::Brush(k) => k,
            BondEffect::Saturation(k) => k,
            BondEffect::FluxLimit(k) => k,
            BondEffect::Ripple(k) => k,
            BondEffect::Heating(k) => k,
            BondEffect::Stiffness(k) => k,
            BondEffect::Leak(k) => k,
            BondEffect::Inflow(k) => k,
            BondEffect::Overflow(k) => k,
            BondEffect::Orifice(k) => k,
            BondEffect::Power(k) => k,
            BondEffect::Store(k) => k,
            BondEffect::DeadZone(k) => k,
            BondEffect::Gain(k) => k,
            BondEffect::ActuatorOffset(k) => k,
            BondEffect::Limit(k) => k,
            BondEffect::ActuatorLag(k) => k,
            BondEffect::ActuatorDelay(k) => k,
            BondEffect::Lag(k) => k,
            BondEffect::Offset(k) => k,
            BondEffect::Drift(k) => k,
            BondEffect::Clip(k) => k,
            BondEffect::Scale(k) => k,
            BondEffect::Delay(k) => k,
            BondEffect::Declared(k) => k,
            BondEffect::Law(k) => k,
            BondEffect::Calibration(k) => k,
        }
    }

    /// The junction an element effect attaches to; `None` for changes of a
    /// parameter and for saturation (which acts on an I).
    pub fn junction(&self) -> Option<Junction> {
        match self {
            BondEffect::Viscous(Viscous { junction })
            | BondEffect::Coulomb(Coulomb { junction })
            | BondEffect::Load(Load { junction })
            | BondEffect::Inertia(Inertia { junction })
            | BondEffect::Coupling(Coupling { junction })
            | BondEffect::Backlash(Backlash { junction })
            | BondEffect::Cogging(Cogging { junction })
            | BondEffect::Brush(Brush { junction }) => Some(*junction),
            BondEffect::Deviation(_)
            | BondEffect::Factor(_)
            | BondEffect::Fault(_)
            | BondEffect::Saturation(_)
            | BondEffect::FluxLimit(_)
            | BondEffect::Ripple(_)
            | BondEffect::Heating(_)
            | BondEffect::Stiffness(_)
            | BondEffect::Leak(_)
            | BondEffect::Inflow(_)
            | BondEffect::Overflow(_)
            | BondEffect::Orifice(_)
            | BondEffect::Power(_)
            | BondEffect::Store(_)
            | BondEffect::DeadZone(_)
            | BondEffect::Gain(_)
            | BondEffect::ActuatorOffset(_)
            | BondEffect::Limit(_)
            | BondEffect::ActuatorLag(_)
            | BondEffect::ActuatorDelay(_)
            | BondEffect::Lag(_)
            | BondEffect::Offset(_)
            | BondEffect::Drift(_)
            | BondEffect::Clip(_)
            | BondEffect::Scale(_)
            | BondEffect::Delay(_)
            | BondEffect::Declared(_)
            | BondEffect::Law(_)
            | BondEffect::Calibration(_) => None,
        }
    }

    /// The candidate (see [`EffectDef::candidate`]).
    pub fn candidate(&self, g: &BondGraph, scales: &Scales) -> Candidate {
        self.def().candidate(g, scales)
    }

    /// `g` with the effect applied at `values` (see [`EffectDef::apply`]).
    ///
    /// # Errors
    /// As [`EffectDef::apply`].
    pub fn apply(
        &self,
        g: &BondGraph,
        c: &Candidate,
        values: &[f64],
    ) -> Result<(BondGraph, Vec<ParamChange>)> {
        self.def().apply(g, c, values)
    }

    /// The parameters the fault trees would name (see
    /// [`EffectDef::qualitative_signature`]).
    pub fn qualitative_signature(&self, g: &BondGraph) -> Option<Vec<QualTarget>> {
        self.def().qualitative_signature(g)
    }

    /// The values at which candidate `c` does nothing at all, from its kind
    /// alone (no graph needed; see [`EffectDef::vanishing_values`]): `None`
    /// for an id no kind writes and for candidates that are not missing elements.
    pub fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
        if c.kind != EffectKind::MissingElement {
            return None;
        }
        let (tag, _) = Tag::read(&c.id)?;
        match tag {
            Tag::Deviation | Tag::Fault | Tag::Declared | Tag::Calibration => None,
            Tag::Viscous => Viscous::vanishing_values(c),
            Tag::Coulomb => Coulomb::vanishing_values(c),
            Tag::Load => Load::vanishing_values(c),
            Tag::Inertia => Inertia::vanishing_values(c),
            Tag::Coupling => Coupling::vanishing_values(c),
            Tag::Backlash => Backlash::vanishing_values(c),
            Tag::Cogging => Cogging::vanishing_values(c),
            Tag::Brush => Brush::vanishing_values(c),
            Tag::Saturation => Saturation::vanishing_values(c),
            Tag::FluxLimit => FluxLimit::vanishing_values(c),
            Tag::Ripple => ModulusRipple::vanishing_values(c),
            Tag::Heating => Heating::vanishing_values(c),
            Tag::Stiffness => Stiffness::vanishing_values(c),
            Tag::Leak => Leak::vanishing_values(c),
            Tag::Inflow => Inflow::vanishing_values(c),
            Tag::Overflow => Overflow::vanishing_values(c),
            Tag::Orifice => Orifice::vanishing_values(c),
            Tag::Power => PowerLoss::vanishing_values(c),
            Tag::Store => Store::vanishing_values(c),
            Tag::DeadZone => DeadZone::vanishing_values(c),
            Tag::Gain => ActuatorGain::vanishing_values(c),
            Tag::ActuatorOffset => ActuatorOffset::vanishing_values(c),
            Tag::Limit => ActuatorLimit::vanishing_values(c),
            Tag::ActuatorLag => ActuatorLag::vanishing_values(c),
            Tag::ActuatorDelay => ActuatorDelay::vanishing_values(c),
            Tag::Lag => SensorLag::vanishing_values(c),
            Tag::Offset => SensorOffset::vanishing_values(c),
            Tag::Drift => SensorDrift::vanishing_values(c),
            Tag::Clip => SensorClip::vanishing_values(c),
            Tag::Scale => SensorScale::vanishing_values(c),
            Tag::Delay => SensorDelay::vanishing_values(c),
            Tag::Law => LawEffect::vanishing_values(c),
        }
    }
}

/// Whether a candidate adds dynamics a fixed step checked on the model
/// without it cannot follow: a contact that closes and opens (backlash)
/// switches a stiff mode on and off, and a linearly implicit step that starts
/// in the gap and ends in contact blows up; a law that quantises an input
/// (`quantise(`) jumps between the input's samples wherever a level is
/// crossed, where the fixed step was chosen for the input's own changes. Such
/// a candidate is simulated with adaptive steps even by a model's copy for
/// fitting.
pub fn needs_adaptive_steps(c: &Candidate) -> bool {
    match Tag::read(&c.id) {
        Some((Tag::Backlash, _)) => true,
        Some((Tag::Law, formula)) => formula.contains("quantise("),
        _ => false,
    }
}

/// The error for a candidate no kind of this model takes.
fn unknown(c: &Candidate) -> BondError {
    bad(
        c,
        "",
        format!(
            "not an effect of this model (expected {} on a matching junction)",
            Tag::expected()
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::offered;
    use crate::library;

    #[test]
    fn every_offered_effect_reads_back_from_its_candidate() {
        for g in [library::dc_motor(), library::buck_motor()] {
            let scales = Scales::of(&g);
            for e in offered(&g) {
                let c = e.candidate(&g, &scales);
                let read = BondEffect::from_candidate(&c, &g).unwrap();
                assert_eq!(read, e, "{}", c.id);
            }
        }
    }

    #[test]
    fn ids_the_graph_cannot_take_are_refused_naming_the_candidate() {
        let g = library::dc_motor();
        let menu = crate::effects::candidates(&g);
        for (id, says) in [
            ("foo@1m", "not an effect of this model"),
            ("coulomb@zz", "no junction 'zz'"),
            ("coulomb@1e", "not an effect of this model"),
            ("brush@1m", "not an effect of this model"),
            ("cogging@L", "'L' is not a 1-junction"),
            ("backlash@zz", "no junction 'zz'"),
            ("backlash@1e", "not an effect of this model"),
            ("deviation:zz", "no parameter or modulus input 'zz'"),
            ("fault:zz", "no parameter or modulus input 'zz'"),
            ("saturation@R", "no I element 'R'"),
        ] {
            let mut c = menu[0].clone();
            c.id = id.to_string();
            let err = BondEffect::from_candidate(&c, &g).unwrap_err();
            let text = err.to_string();
            assert!(text.starts_with(&format!("effect '{id}': ")), "{text}");
            assert!(text.contains(says), "{text}");
        }
    }
}
