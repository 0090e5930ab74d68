//! The seam between the measurement loop and a simulator: a [`Model`]
//! predicts a recording's measured outputs from its inputs, and offers the
//! [`Candidate`] effects it could be missing.

use crate::effect::{Candidate, Effect};
use crate::error::Result;
use crate::explain::estimate::MissingSignal;
use crate::explain::screen::Law;
use crate::recording::Recording;

/// A model's prediction of a recording's measured outputs, at the recording's times.
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// Output names, as in recordings.
    pub names: Vec<String>,
    /// One series per output, one value per sample of the recording.
    pub values: Vec<Vec<f64>>,
}

impl Prediction {
    /// The series of an output, by name.
    pub fn get(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.values[i].as_slice())
    }

    /// `(measured − predicted) / scale` of each output in `names`, output after
    /// output, into `out` (`names.len()` × samples long): the residual every fit
    /// of the loop minimises.
    ///
    /// # Errors
    /// [`crate::CoreError::Model`] when the prediction lacks one of the outputs.
    pub fn residuals_into(
        &self,
        names: &[String],
        measured: &[&[f64]],
        scale: &[f64],
        out: &mut [f64],
    ) -> Result<()> {
        let n = out.len() / names.len().max(1);
        for (j, name) in names.iter().enumerate() {
            let p = self.get(name).ok_or_else(|| {
                crate::CoreError::model(format!("the model did not predict output '{name}'"))
            })?;
            for (k, o) in out[j * n..(j + 1) * n].iter_mut().enumerate() {
                *o = (measured[j][k] - p[k]) / scale[j];
            }
        }
        Ok(())
    }
}

/// A physical model that can be held against a recording.
///
/// Implemented by the bond-graph crate (a model file or a built-in) and the
/// cloth crate (a scene). Everything the loop needs goes through here, so the
/// loop ([`crate::explain()`]) knows nothing of bonds or particles.
pub trait Model: Send + Sync {
    /// A short name for reports (`dc-motor`).
    fn name(&self) -> String;

    /// The measured outputs the model predicts, by recording name.
    fn outputs(&self) -> Vec<String>;

    /// The unit of an output (`A`, `rad/s`), for plots and reports.
    fn unit(&self, output: &str) -> String {
        let _ = output;
        String::new()
    }

    /// The inputs the model is driven by, by recording name (`V`, `m`):
    /// whatever of them a recording holds, the judge holds the residuals
    /// against (a model error answers what the input did; noise does not).
    /// Empty (the default) for a model driven by nothing recorded.
    fn inputs(&self) -> Vec<String> {
        Vec::new()
    }

    /// The model's time constants (s) near the start of `rec`: the judge
    /// says a recording cannot be judged when its samples lie too far apart
    /// to see them, or it is too short to hold any (a time column in ms).
    /// Empty (the default) when the model does not know them.
    fn time_constants(&self, rec: &Recording) -> Vec<f64> {
        let _ = rec;
        Vec::new()
    }

    /// Predicts the outputs at the recording's times, driven by the
    /// recording's inputs (those the model takes and the recording holds).
    ///
    /// # Errors
    /// [`crate::CoreError::Model`] when the model cannot simulate the recording.
    fn predict(&self, rec: &Recording) -> Result<Prediction> {
        self.predict_with(rec, &[])
    }

    /// Predicts with candidate effects applied at the given parameter values:
    /// the inner loop of every fit, so it should be fast.
    ///
    /// # Errors
    /// [`crate::CoreError::Model`] when the model cannot simulate the recording
    /// with these effects (e.g. a parameter value that makes it stiff or singular).
    fn predict_with(&self, rec: &Recording, effects: &[(&Candidate, &[f64])])
    -> Result<Prediction>;

    /// The effects the model could be missing, each with its parameters,
    /// units, initial values and bounds.
    fn candidates(&self) -> Vec<Candidate>;

    /// The candidates to fit to `rec`: [`Model::candidates`] with their
    /// scales and bounds taken from the model driven by the recording's
    /// inputs, not from the inputs' defaults (which the recording
    /// overrides). The default is [`Model::candidates`]; ids are the same.
    fn candidates_for(&self, rec: &Recording) -> Vec<Candidate> {
        let _ = rec;
        self.candidates()
    }

    /// The model's own unknowns — parameters marked free and initial states
    /// to be fitted — as one candidate of kind
    /// [`EffectKind::Calibration`](crate::EffectKind::Calibration) that
    /// [`Model::predict_with`] and [`Model::with_effects`] accept like any
    /// effect. [`crate::calibrate()`] fits it. `None` (the default) when the
    /// model has no unknowns.
    fn free_parameters(&self) -> Option<Candidate> {
        None
    }

    /// A new model with the effects built in.
    ///
    /// # Errors
    /// [`crate::CoreError::Model`] when an effect does not fit the model.
    fn with_effects(&self, effects: &[Effect]) -> Result<Box<dyn Model>>;

    /// The missing effort (or flow) at each place of the model where one
    /// could act, estimated from `rec` with `effects` applied (the model's
    /// calibration): discovery's first stage
    /// ([`crate::explain::estimate`]). `outputs` are the outputs to hold
    /// the model against and `sigma` their noise (one per output, in their
    /// units). Empty (the default) when the model cannot estimate it.
    ///
    /// # Errors
    /// [`crate::CoreError::Model`] when the model cannot be simulated.
    fn missing_signals(
        &self,
        rec: &Recording,
        effects: &[(&Candidate, &[f64])],
        outputs: &[String],
        sigma: &[f64],
    ) -> Result<Vec<MissingSignal>> {
        let _ = (rec, effects, outputs, sigma);
        Ok(Vec::new())
    }

    /// The white measurement noise of each of `outputs` (name, σ in its unit)
    /// that the model with `effects` applied finds likeliest on `rec` when a
    /// free effort or flow acts at its place that explains most: what a model
    /// lacking nothing else would still leave — a noise floor that an
    /// oversampled resonance's own fast content cannot inflate. `sigma` are
    /// the floors so far (the search's scale). Empty (the default) when the
    /// model cannot say.
    ///
    /// # Errors
    /// [`crate::CoreError::Model`] when the model cannot be simulated.
    fn measurement_noise(
        &self,
        rec: &Recording,
        effects: &[(&Candidate, &[f64])],
        outputs: &[String],
        sigma: &[f64],
    ) -> Result<Vec<(String, f64)>> {
        let _ = (rec, effects, outputs, sigma);
        Ok(Vec::new())
    }

    /// A law the screen found ([`crate::explain::screen`]) as a candidate
    /// effect this model can build in, started at the regression's values
    /// and bounded by the data's scale: discovery's third stage confirms it
    /// by simulation like any candidate. `None` (the default) when the model
    /// cannot build laws.
    fn law_candidate(&self, law: &Law) -> Option<Candidate> {
        let _ = law;
        None
    }

    /// The model's own predictability band on `rec`: per output and per
    /// sample, how far (in the output's unit, ≥ 0) a prediction of the same
    /// nominal model may lie from another equally valid one — the spread
    /// between a run at the model's step and at half of it, or under tiny
    /// perturbations of the initial state. A cloth that snaps taut on its
    /// pins branches at each snap, and its predictions at h and h/2 can
    /// differ by centimetres: [`crate::compare()`] counts as model failure
    /// only what lies beyond both this spread and the measurement noise.
    /// `None` (the default) when the model's prediction is sharp.
    ///
    /// # Errors
    /// [`crate::CoreError::Model`] when the model cannot simulate the recording.
    fn prediction_spread(&self, rec: &Recording) -> Result<Option<Prediction>> {
        let _ = rec;
        Ok(None)
    }

    /// How far the model's own numerics move its prediction on `rec`: per output and per
    /// sample (in the output's unit, ≥ 0), the largest distance of the nominal prediction
    /// from a run at half the model's step and from a run with its start nudged far below
    /// any measurement — no envelope and no safety factor, unlike
    /// [`Model::prediction_spread`]. What an effect of that size on a recording of the
    /// real system cannot be told from. `None` (the default) when the prediction is sharp.
    ///
    /// # Errors
    /// [`crate::CoreError::Model`] when the model cannot simulate the recording.
    fn numerical_error(&self, rec: &Recording) -> Result<Option<Prediction>> {
        let _ = rec;
        Ok(None)
    }

    /// The model as the text of its file format (a bond-graph TOML), if it is
    /// file-based; after [`Model::with_effects`] it holds the new elements.
    fn to_file_text(&self) -> Option<String> {
        None
    }

    /// The file extension of [`Model::to_file_text`] (`toml`).
    fn file_extension(&self) -> &'static str {
        "txt"
    }

    /// Whether candidate `c` at `values` leaves the model exactly as it is (a
    /// point mass of 0 kg, a parameter at its current value): a screen then
    /// reuses the nominal prediction instead of simulating it again. `false`
    /// (the default) when the model cannot tell.
    fn vanishes(&self, c: &Candidate, values: &[f64]) -> bool {
        let _ = (c, values);
        false
    }

    /// The model as fits on `rec` should simulate it: the same predictions
    /// (within a small, checked tolerance), computed so that they are a
    /// smooth function of every parameter a fit moves. An adaptive ODE solver
    /// changes its step sequence when a parameter moves, which puts noise of
    /// the order of its tolerance into every finite difference: a fit of a
    /// nonlinear model then crawls (on Silverbox, 50 iterations to a point
    /// ten better ones away). A bond graph answers with a fixed-step model
    /// whose grid is checked against the adaptive run of the model as given
    /// (see `BondModel::for_fitting`). `None` (the default): the model as
    /// given is already smooth, or no grid was good enough.
    fn for_fitting(&self, rec: &Recording) -> Option<Box<dyn Model>> {
        let _ = rec;
        None
    }

    /// The loosest fit tolerances worth using on this model: `(ftol, xtol)`
    /// of [`FitOptions`](crate::fit::FitOptions) (relative cost change,
    /// step in parameter scales). A model whose predictions are only as
    /// exact as an iterative solver's tolerance (a cloth) gains nothing from
    /// fitting below it, and each iteration costs whole simulations;
    /// [`explain`](crate::explain::explain) never fits tighter than this.
    /// `None` (the default): the options as given.
    fn fit_tolerances(&self) -> Option<(f64, f64)> {
        None
    }

    /// The finite-difference step a fit should take in each parameter, as a
    /// fraction of its scale ([`EffectParam::scale`](crate::EffectParam)),
    /// when the model's predictions are only as exact as an iterative
    /// solver's tolerance: a step must move the prediction well above the
    /// solver's own scatter, or the Jacobian is that scatter (a cloth solved
    /// to 1e-4 stretch: a compliance moved by 1e-4 of its scale changes the
    /// markers less than the solver's stopping point does, and the fit stays
    /// at its start of 0). `None` (the default): the fitter's and screen's
    /// own steps (1e-4 and 1e-3 of the scale).
    fn fd_step(&self) -> Option<f64> {
        None
    }

    /// Whether a prediction costs so much more than a fit's algebra (a cloth simulated
    /// step by step through its constraint solver) that fits should update their Jacobian
    /// by secant steps between finite-difference ones ([`crate::fit::FitOptions::secant`]):
    /// a fit's step then costs one prediction instead of one per parameter. Fits still end
    /// on, and take their standard errors from, finite differences. Default `false`.
    fn costly_predictions(&self) -> bool {
        false
    }

    /// How the loop's results read for this model: text, JSON and the report. The default
    /// reads them output by output ([`crate::story::PerOutput`]).
    fn story(&self) -> &dyn crate::story::Story {
        &crate::story::PerOutput
    }

    /// Reads a recording for this model from a file: by default a signals file (CSV or
    /// MCAP, [`crate::io::read_recording_path`]); a model whose recordings come in another
    /// form (a cloth's marker files) reads them its own way, checked against itself.
    ///
    /// # Errors
    /// The reader's errors, naming the file and the line, field or message.
    fn read_recording(&self, path: &std::path::Path) -> Result<Recording> {
        crate::io::read_recording_path(path)
    }

    /// Findings worth telling the user before the loop runs on `rec`: by default the
    /// outputs the recording does not measure.
    fn notes(&self, rec: &Recording) -> Vec<String> {
        self.outputs()
            .iter()
            .filter(|o| rec.signal(o).is_none())
            .map(|o| format!("the recording does not measure output `{o}`: it is left out"))
            .collect()
    }

    /// Whether a candidate's qualitative signature (fault tree, temporal
    /// signature) agrees with the residuals the model leaves on `rec`;
    /// `None` when the model has no qualitative reasoning for it.
    fn qualitative_agreement(&self, rec: &Recording, candidate: &Candidate) -> Option<bool> {
        let _ = (rec, candidate);
        None
    }

    /// [`qualitative_agreement`](Model::qualitative_agreement) with its
    /// reason in plain words (which outputs deviated which way, which
    /// parameters the diagnosis points at, and what the candidate would look
    /// like), for the report and the text beside a "signature agrees" or
    /// "signature disagrees" tag. By default the agreement alone with an
    /// empty reason; models with qualitative reasoning override this.
    fn qualitative_check(
        &self,
        rec: &Recording,
        candidate: &Candidate,
    ) -> Option<QualitativeCheck> {
        self.qualitative_agreement(rec, candidate)
            .map(|agrees| QualitativeCheck {
                agrees,
                reason: String::new(),
            })
    }
}

/// The result of a model's qualitative check of a candidate
/// ([`Model::qualitative_check`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct QualitativeCheck {
    /// Whether the qualitative diagnosis points at the candidate.
    pub agrees: bool,
    /// Why, in plain words ("i rose and omega fell first; the fault trees
    /// point at R+, L+; viscous friction would show as beta+"); may be empty.
    pub reason: String,
}
