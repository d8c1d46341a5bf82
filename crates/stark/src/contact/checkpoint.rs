//! The contact part of a checkpoint: what the next step depends on that building the scene again
//! does not recreate. Pairs, lagged friction and candidates are recomputed from the positions at
//! the start of every step, so they are not saved.

use super::{Contact, ContactStats};
use serde::{Deserialize, Serialize};

#[derive(Serialize, Deserialize)]
struct SavedContact {
    /// Adaptive barrier stiffness κ and its initial value (its growth is bounded by it), N/m.
    kappa: f64,
    kappa_initial: f64,
    /// Enabled object pairs and friction coefficients (changeable between steps).
    enabled: Vec<bool>,
    friction: Vec<f64>,
    /// Statistics of the last step (the step log's next line starts from them).
    stats: ContactStats,
}

impl Contact {
    pub(super) fn save_checkpoint_state(&self) -> Vec<u8> {
        crate::energy::encode_state(&SavedContact {
            kappa: self.kappa,
            kappa_initial: self.kappa_initial,
            enabled: self.enabled.clone(),
            friction: self.friction.clone(),
            stats: self.stats,
        })
    }

    pub(super) fn restore_checkpoint_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        let saved: SavedContact = crate::energy::decode_state(bytes)?;
        crate::energy::restore_vec(&mut self.enabled, saved.enabled, "object pairs")?;
        crate::energy::restore_vec(&mut self.friction, saved.friction, "object pairs")?;
        self.kappa = saved.kappa;
        self.kappa_initial = saved.kappa_initial;
        self.stats = saved.stats;
        Ok(())
    }
}
