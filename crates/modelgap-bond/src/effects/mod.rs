//! Candidate effects of a bond graph: what the model may be missing, and the
//! graph edits that add it.
//!
//! [`candidates`] lists, for a graph, every effect the measurement loop may
//! fit: a deviation of each parameter, an abrupt change of each parameter at
//! an unknown time (a fault), and the physical elements the model may lack,
//! attached where they make physical sense. [`apply`] turns a candidate and
//! its parameter values into an edited graph (elements, bonds and parameters
//! appended; old ids stay valid) plus the parameter changes an abrupt fault
//! makes during a simulation.
//!
//! # Where element candidates attach
//!
//! The domain of a 1-junction comes from the I elements bonded to it: the
//! unit of a parameter in the I's law says what it stores. A unit with the
//! token `H` (or `Wb/A`) is electrical, `kg m^2` (also `kg*m^2`, `kg·m²`) is
//! rotational, `kg` is translational. A model author makes the domain
//! explicit by giving the inertia parameter its unit. Only 1-junctions with
//! such an I get element candidates; a junction without one (the far side of
//! a transformer, a 0-junction) gets none, to keep the menu short and every
//! edit well-posed (an element on a common-flow junction with an inertia
//! never loses integral causality).
//!
//! - rotational and translational 1-junctions: viscous friction, Coulomb
//!   friction (smoothed), a constant load, extra inertia, a flexible coupling
//!   to a second inertia, backlash (part of the inertia behind a gap);
//!   rotational ones also cogging torque;
//! - electrical 1-junctions: a brush/contact voltage drop;
//! - each electrical I with a linear law: magnetic saturation.
//!
//! # Scales
//!
//! Each parameter carries a `scale` (a typical size: finite-difference steps
//! and scaling in the fit) and bounds. Scales come from the model itself: a
//! start-up from rest under the default inputs, simulated over five slowest
//! time constants, gives each 1-junction a *typical* effort and flow (the
//! largest magnitude on its bonds at the steady state; for the DC motor's
//! shaft the friction torque `k i_ss`, for its armature loop the supply
//! voltage) and a *peak* effort and flow (the largest over the start-up: the
//! stall torque `k V / R` of the motor, nearly). An effort strength (a
//! friction torque, a load, a brush drop) has the typical effort as its scale,
//! kept within [10⁻³, 10⁻¹] of the peak, and may reach the peak effort (a
//! friction beyond what the drive can ever apply would hold the machine
//! still). A model that cannot be simulated gets scale 1 everywhere.
//!
//! # Files
//!
//! One file per kind of effect, each a small struct naming where it acts
//! and implementing [`EffectDef`] (offer, candidate, edit, qualitative
//! signature, vanishing values):
//!
//! - [`deviation`](Deviation) (`deviation:<p>`), [`factor`](Factor) (`deviation:<u>`,
//!   a modulus input), [`fault`](Fault) (`fault:<p>`, `fault:<u>`);
//! - on junctions: [`viscous`](Viscous), [`coulomb`](Coulomb), [`load`](Load),
//!   [`inertia`](Inertia), [`coupling`](Coupling), [`backlash`](Backlash),
//!   [`cogging`](Cogging),
//!   [`brush`](Brush); on an I: [`saturation`](Saturation) (the current grows by a power of the
//!   flux) and [`flux-limit`](FluxLimit) (towards a flux the core cannot pass); on a GY between a
//!   winding and a shaft: [`ripple`](ModulusRipple) (its modulus varies around a
//!   turn: a torque and back-EMF ripple); on an electrical R:
//!   [`heating`](Heating) (it rises with the energy it dissipates); on a C, in any
//!   domain: [`stiffness`](Stiffness) (a cubic term); on storage nodes
//!   ([`Node`]: a 0-junction with a C, any domain): [`leak`](Leak),
//!   [`inflow`](Inflow), [`overflow`](Overflow), [`store`](Store) (a second
//!   storage behind a resistance: a second thermal mass, a hydraulic
//!   compliance), on hydraulic ones [`orifice`](Orifice) (√Δp outflow), and on
//!   thermal ones [`power`](PowerLoss) (a loss growing as `|T|^p`: natural
//!   convection, radiation);
//! - on a source an input drives, in any domain: [`deadzone`](DeadZone),
//!   [`gain`](ActuatorGain) (the actuator delivers `k` times its command),
//!   [`actuator-offset`](ActuatorOffset) (its command plus a constant) and
//!   [`limit`](ActuatorLimit) (it saturates at `±v_max`),
//!   [`actuator-lag`](ActuatorLag) (it follows its command through a first-order
//!   lag) and [`actuator-delay`](ActuatorDelay) (a delay behind);
//! - on every output: [`lag`](SensorLag) (a first-order lag in its sensor) and
//!   [`offset`](SensorOffset) (a constant added to its reading),
//!   [`drift`](SensorDrift) (its zero moves at a steady rate),
//!   [`clip`](SensorClip) (it reads nothing beyond `[lower, upper]`) and
//!   [`scale`](SensorScale) (its reading `k` times the value) and
//!   [`delay`](SensorDelay) (it reports late, any fraction of a sample);
//! - declared by the model file (`[[candidates]]`): [`declared`](Declared);
//! - never on the menu: [`calibration`](Calibration), the graph's own unknowns
//!   (free parameters and initial states) that calibration fits.
//!
//! Around them: `def` (the trait [`EffectDef`]), `bond_effect` (the enum
//! [`BondEffect`] over the kinds, and [`BondEffect::from_candidate`], the one
//! place an id is read), `tag` (the id prefixes, written and read), `menu`
//! ([`candidates`]: each kind's offers in turn), `domain` ([`Domain`]),
//! `junction` ([`Junction`]: where element effects attach), `edit` (what the
//! edits share: fresh names, new parameters, attached one-ports) and
//! `scales` ([`Scales`]: the model's own scales).

mod actuator;
mod backlash;
mod bias;
mod bond_effect;
mod brush;
mod calibration;
mod clip;
mod cogging;
mod coulomb;
mod coupling;
mod deadzone;
mod declared;
mod def;
mod delay;
mod deviation;
mod domain;
mod drift;
mod edit;
mod factor;
mod fault;
mod flux_limit;
mod gain;
mod heating;
mod inertia;
mod inflow;
mod junction;
mod lag;
mod law;
mod leak;
mod limit;
mod load;
mod menu;
mod node;
mod offset;
mod orifice;
mod overflow;
mod power;
mod ripple;
mod saturation;
mod scale;
mod scales;
mod stiffness;
mod store;
mod tag;
mod viscous;

use modelgap_core::Candidate;

use crate::error::Result;
use crate::graph::BondGraph;
use crate::simulate::ParamChange;

pub use actuator::{ActuatorDelay, ActuatorLag};
pub use backlash::Backlash;
pub use bias::ActuatorOffset;
pub use bond_effect::{BondEffect, needs_adaptive_steps};
pub use brush::Brush;
pub use calibration::Calibration;
pub use clip::SensorClip;
pub use cogging::Cogging;
pub(crate) use cogging::is_periodic;
pub use coulomb::Coulomb;
pub use coupling::Coupling;
pub use deadzone::DeadZone;
pub use declared::Declared;
pub use def::{EffectDef, QualTarget};
pub use delay::SensorDelay;
pub use deviation::Deviation;
pub use domain::Domain;
pub use drift::SensorDrift;
pub(crate) use edit::attach;
pub use factor::Factor;
pub use fault::{Fault, Faulted};
pub use flux_limit::FluxLimit;
pub use gain::ActuatorGain;
pub use heating::Heating;
pub use inertia::Inertia;
pub use inflow::Inflow;
pub use junction::{Junction, junction_domain};
pub use lag::SensorLag;
pub use law::{LawEffect, law_candidate};
pub use leak::Leak;
pub use limit::ActuatorLimit;
pub use load::Load;
pub(crate) use menu::place;
pub use menu::{candidates, candidates_with, offered};
pub use node::{Node, NodeKind};
pub use offset::SensorOffset;
pub use orifice::Orifice;
pub use overflow::Overflow;
pub use power::PowerLoss;
pub use ripple::ModulusRipple;
pub use saturation::Saturation;
pub use scale::SensorScale;
pub use scales::Scales;
pub use stiffness::Stiffness;
pub use store::Store;
pub use viscous::Viscous;

/// The name of the fault-time parameter of every abrupt-change candidate.
///
/// The measurement loop recognises a parameter with this name and unit `s`,
/// replaces its bounds with the recording's time span and searches it by
/// scanning (a local fit cannot find a fault time).
pub const T_FAULT: &str = "t_fault";

/// Smoothing speed (rad/s) of the Coulomb friction on a rotational junction:
/// the friction torque is `tau_c · tanh(ω / ω_s)`, full strength above a few
/// `ω_s`. Fixed (not fitted) and written into the graph as a parameter that a
/// user can edit.
pub const COULOMB_SMOOTHING_RAD_S: f64 = 1.0;

/// Smoothing speed (m/s) of the Coulomb friction on a translational junction.
pub const COULOMB_SMOOTHING_M_S: f64 = 1e-3;

/// Smoothing current (A) of the brush/contact voltage drop
/// `v_b · tanh(i / i_s)`. Fixed, written into the graph as a parameter.
pub const CONTACT_SMOOTHING_A: f64 = 1e-2;

/// Number of start values the fit tries for the cogging period count
/// `N_cog` across its bounds [2, 24]: the even counts, since the cogging
/// count of a motor is the least common multiple of its slot and (even)
/// pole counts. A local fit cannot find a period count from afar.
pub const COGGING_GRID: usize = 12;

/// Applies a candidate at `values`: the edited graph, and the parameter
/// changes to make during a simulation (abrupt changes only).
///
/// Reads the candidate ([`BondEffect::from_candidate`]) and applies its
/// kind ([`EffectDef::apply`]). Deviations set the parameter (a modulus
/// input gets a factor parameter `<u>_factor` on its MTF/MGY law); abrupt
/// changes leave the graph as is (a modulus gets its factor at 1) and return
/// a [`ParamChange`] at `t_fault`; missing elements append elements, bonds
/// and parameters (named `<stem>_<junction>`, with `_2`, `_3`, … when
/// taken), or change the law of the junction's I (extra inertia,
/// saturation). Ids are append-only, so the ids of `g` stay valid in the
/// result.
///
/// # Errors
/// [`BondError::BadEffect`](crate::BondError::BadEffect) naming the
/// candidate and the parameter for a candidate this graph does not offer
/// (unknown parameter, junction or element), a wrong number of values, or a
/// value that is not finite or outside its bounds; graph errors if the edit
/// breaks the graph (a bug).
///
/// # Example
/// ```
/// # use modelgap_bond::{effects, library, CompiledModel};
/// let motor = library::dc_motor();
/// let menu = effects::candidates(&motor);
/// let coulomb = menu.iter().find(|c| c.id == "coulomb@1m").unwrap();
/// let (edited, changes) = effects::apply(&motor, coulomb, &[0.01]).unwrap();
/// assert!(changes.is_empty());
/// assert!(edited.find("coulomb_1m").is_some());
/// assert!(CompiledModel::new(&edited).is_ok());
/// ```
pub fn apply(
    g: &BondGraph,
    candidate: &Candidate,
    values: &[f64],
) -> Result<(BondGraph, Vec<ParamChange>)> {
    BondEffect::from_candidate(candidate, g)?.apply(g, candidate, values)
}

/// The values at which a missing-element candidate has no effect at all:
/// its strengths (viscous `b`, friction, load, inertia increment, cogging
/// amplitude, brush drop, saturation coefficient) at 0 and any other
/// parameter (the cogging period count) at its initial value. `None` for
/// deviations, abrupt changes and the coupling (a second inertia cannot
/// vanish: `J2 → 0` is singular). See [`BondEffect::vanishing_values`].
pub fn vanishing_values(c: &Candidate) -> Option<Vec<f64>> {
    BondEffect::vanishing_values(c)
}
