//! The contact part of a checkpoint: what the next step depends on that building the scene again
//! does not recreate. Pairs, lagged friction and candidates are recomputed from the positions at
//! the start of every step, so they are not saved.

use super::stiffness::PairStiffness;
use super::{Contact, ContactStats};
use serde::{Deserialize, Serialize};

#[derive(Serialize, Deserialize)]
struct SavedContact {
    /// Barrier stiffness κ of every pair of objects: current, initial (its growth is bounded by
    /// it), inertial floor and whether its load was measured.
    kappa: PairStiffness,
    /// Mean contact mass of each object, kg (the kinematic objects are those with 0).
    object_masses_kg: Vec<f64>,
    /// Enabled object pairs and friction coefficients (changeable between steps).
    enabled: Vec<bool>,
    friction: Vec<f64>,
    /// Statistics of the last step (the step log's next line starts from them).
    stats: ContactStats,
}

impl Contact {
    pub(super) fn save_checkpoint_state(&self) -> Vec<u8> {
        crate::energy::encode_state(&SavedContact {
            kappa: self.kappa.clone(),
            object_masses_kg: self.object_masses_kg.clone(),
            enabled: self.enabled.clone(),
            friction: self.friction.clone(),
            stats: self.stats,
        })
    }

    pub(super) fn restore_checkpoint_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        let saved: SavedContact = crate::energy::decode_state(bytes)?;
        crate::energy::restore_vec(&mut self.enabled, saved.enabled, "object pairs")?;
        crate::energy::restore_vec(&mut self.friction, saved.friction, "object pairs")?;
        if saved.kappa.objects() != self.objects.len() {
            return Err(format!(
                "the checkpoint has barrier stiffnesses for {} contact objects, the scene {}",
                saved.kappa.objects(),
                self.objects.len()
            ));
        }
        self.kappa = saved.kappa;
        self.object_masses_kg = saved.object_masses_kg;
        self.stats = saved.stats;
        Ok(())
    }
}
