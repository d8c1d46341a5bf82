//! Objects without a model of their own: labelled nodes, and user energies.

use super::*;

impl Simulation {
    /// Add deformable nodes at `positions` (their rest positions too) as a labelled object.
    pub fn add_nodes(&mut self, label: &str, positions: &[Vector3<f64>]) -> Result<NodeSetHandle> {
        if label.is_empty() || self.deformables.set_by_label(label).is_some() {
            return Err(StarkError::InvalidInput(format!(
                "object label '{label}' is empty or already used"
            )));
        }
        if let Some(i) = positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(StarkError::InvalidInput(format!(
                "node {i} of '{label}' has a non-finite position"
            )));
        }
        if positions.is_empty() {
            return Err(StarkError::InvalidInput(format!("object '{label}' has no nodes")));
        }
        let first = self.nodes.push(positions);
        let handle = NodeSetHandle {
            index: self.deformables.sets.len() as u32,
            first: first as u32,
            len: positions.len() as u32,
        };
        self.deformables.sets.push((label.to_string(), handle));
        Ok(handle)
    }

    /// Positions of an object's nodes, m.
    pub fn positions(&self, set: NodeSetHandle) -> &[Vector3<f64>] {
        &self.nodes.x[set.range()]
    }

    /// Velocities of an object's nodes, m/s.
    pub fn velocities(&self, set: NodeSetHandle) -> &[Vector3<f64>] {
        &self.nodes.v[set.range()]
    }

    /// Set the velocity of every node of an object, m/s.
    pub fn set_velocity(&mut self, set: NodeSetHandle, v: Vector3<f64>) {
        for i in set.range() {
            self.nodes.v[i] = v;
        }
    }

    /// Add a user energy term (e.g. a [`PotentialTerm`](crate::energy::PotentialTerm)).
    pub fn add_term(&mut self, term: Box<dyn EnergyTerm>) {
        self.custom.push(term);
    }

    /// Add a user energy with run-time generated derivatives (README "Your own energy"):
    /// `traced` comes from [`trace_element`](crate::energy::trace_element), every element lists
    /// its nodes (deformable nodes, rigid-body mesh vertices or [`Node::Rigid`] points), and
    /// `params` gives one value per name (shared) or one per name and element.
    pub fn add_user_energy(
        &mut self,
        name: &str,
        elements: &[Vec<Node>],
        param_names: Vec<String>,
        params: &[f64],
        traced: crate::energy::symbolic::TracedEnergy,
    ) -> Result<UserEnergyHandle> {
        for (i, el) in elements.iter().enumerate() {
            for node in el {
                let ok = match *node {
                    Node::Point(k) => (k as usize) < self.nodes.len(),
                    Node::Rigid { body, local } => {
                        (body as usize) < self.bodies.len() && local.iter().all(|c| c.is_finite())
                    }
                    Node::AngularVelocity(body) => (body as usize) < self.bodies.len(),
                    Node::World(p) => p.iter().all(|c| c.is_finite()),
                };
                if !ok {
                    return Err(StarkError::InvalidInput(format!(
                        "energy '{name}': element {i} refers to {node:?}, but the simulation has {} nodes and {} bodies",
                        self.nodes.len(),
                        self.bodies.len()
                    )));
                }
            }
        }
        let term = user_energy::user_energy_term(name, elements, param_names, params, traced)?;
        self.user_energies.push(term);
        Ok(UserEnergyHandle(self.user_energies.len() as u32 - 1))
    }

    /// A user energy added with [`Simulation::add_user_energy`].
    pub fn user_energy(&self, h: UserEnergyHandle) -> Result<&dyn UserEnergyTerm> {
        let len = self.user_energies.len();
        self.user_energies
            .get(h.0 as usize)
            .map(|t| &**t)
            .ok_or(StarkError::InvalidHandle {
                kind: "user energy",
                index: h.0 as usize,
                len,
            })
    }

    /// Change a parameter of a user energy (one value, or one per element); takes effect from
    /// the next step.
    pub fn set_user_energy_param(&mut self, h: UserEnergyHandle, name: &str, values: &[f64]) -> Result<()> {
        let len = self.user_energies.len();
        self.user_energies
            .get_mut(h.0 as usize)
            .ok_or(StarkError::InvalidHandle {
                kind: "user energy",
                index: h.0 as usize,
                len,
            })?
            .set_param(name, values)
    }
}
