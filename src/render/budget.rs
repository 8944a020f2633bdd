//! When a render stops: samples, seconds, photons or an estimated error, whichever comes first.

use crate::Error;

/// When to stop rendering. With several set, whichever comes first.
#[derive(Debug, Clone, Copy, Default)]
pub struct Budget {
    pub spp: Option<u64>,
    pub seconds: Option<f64>,
    /// Photons emitted in total.
    pub photons: Option<u64>,
    /// Stop once the estimated relMSE (docs/error-estimate.md) is below this; needs one of the
    /// others as a cap.
    pub target_error: Option<f64>,
    /// Adaptive sampling: pixels whose estimated error is below `target_error` stop receiving
    /// camera samples (src/render/adaptive.rs).
    pub adaptive: bool,
}

/// A field of a [`Budget`] (or of a render job), for messages: the library names it as the field, the command line
/// as its flag ([`Budget::check_named`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BudgetField {
    Spp,
    Photons,
    Seconds,
    TargetError,
    Adaptive,
    /// A render job's shard and checkpoint interval (`app::job::RenderJob`).
    Shard,
    CheckpointEvery,
}

impl BudgetField {
    /// The field's name in [`Budget`].
    pub fn field_name(self) -> &'static str {
        match self {
            BudgetField::Spp => "spp",
            BudgetField::Photons => "photons",
            BudgetField::Seconds => "seconds",
            BudgetField::TargetError => "target_error",
            BudgetField::Adaptive => "adaptive",
            BudgetField::Shard => "shard",
            BudgetField::CheckpointEvery => "checkpoint_every",
        }
    }
}

impl Budget {
    /// This budget, or when it sets no samples, seconds, photons or error, the scene's sample
    /// count (else 64 samples per pixel), as `hppm render` renders a scene given no budget.
    pub fn or_scene_spp(mut self, scene_spp: Option<u32>) -> Self {
        let none_set = self.spp.is_none()
            && self.seconds.is_none()
            && self.photons.is_none()
            && self.target_error.is_none();
        if none_set {
            self.spp = Some(scene_spp.map_or(64, u64::from));
        }
        self
    }

    /// Refuses a budget that would render nothing or never end, before any work.
    pub fn check(&self) -> Result<(), Error> {
        self.check_named(BudgetField::field_name)
    }

    /// As [`Budget::check`], each field called by `name` in the message.
    pub fn check_named(&self, name: impl Fn(BudgetField) -> &'static str) -> Result<(), Error> {
        use BudgetField::*;
        let refuse = |m: String| Err(Error::Other(m));
        if self.spp == Some(0) {
            return refuse(format!("{} must be at least 1", name(Spp)));
        }
        if self.photons == Some(0) {
            return refuse(format!("{} must be at least 1", name(Photons)));
        }
        if let Some(s) = self.seconds
            && !(s.is_finite() && s > 0.0)
        {
            return refuse(format!(
                "{} must be a positive, finite number of seconds, got {s}",
                name(Seconds)
            ));
        }
        if self.adaptive && self.target_error.is_none() {
            return refuse(format!(
                "{} needs {}: pixels whose estimated error is below the target stop receiving \
                 samples",
                name(Adaptive),
                name(TargetError)
            ));
        }
        if let Some(e) = self.target_error
            && !(e.is_finite() && e > 0.0)
        {
            return refuse(format!(
                "{} must be a positive, finite relMSE, got {e}",
                name(TargetError)
            ));
        }
        if self.spp.is_none() && self.seconds.is_none() && self.photons.is_none() {
            let caps = format!("{}, {} or {}", name(Seconds), name(Spp), name(Photons));
            return refuse(if self.target_error.is_some() {
                format!(
                    "{} needs a cap as well: give {caps} (an estimate may never reach the \
                     target on a scene whose error falls slowly)",
                    name(TargetError)
                )
            } else {
                format!("no budget: give {caps}")
            });
        }
        Ok(())
    }
}
