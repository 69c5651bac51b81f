//! Building a [`PreparedTrain`]: its index maps, its choice of dense or sparse
//! factors, its sizes, and a [`Workspace`] sized for it.

use super::*;

impl PreparedTrain {
    /// Prepare. `inputs` are the links whose speed each scenario prescribes,
    /// `accelerated` those whose acceleration it prescribes (eq. 8), `driving`
    /// those whose torque is solved (eq. 10); each holds F = coordinates -
    /// gear pairs - extras links.
    ///
    /// # Errors
    /// Wrong counts, the frame or a repeated link among them; the mass-matrix
    /// errors of [`MassModel::new`].
    pub fn new(
        train: &Train,
        inputs: &[LinkId],
        accelerated: &[LinkId],
        driving: &[LinkId],
        extras: &[Extra],
    ) -> Result<Self> {
        let mut plan = Self::for_analysis(train, inputs, accelerated, driving, extras)?;
        plan.mass = MassModel::new(train)?;
        Ok(plan)
    }

    /// As [`PreparedTrain::new`] for one analysis that supplies its \[M\]
    /// whole in each scenario (or none): no mass model is built, so no mass
    /// data is asked for.
    ///
    /// # Errors
    /// Wrong counts, the frame or a repeated link among the links.
    pub fn for_analysis(
        train: &Train,
        inputs: &[LinkId],
        accelerated: &[LinkId],
        driving: &[LinkId],
        extras: &[Extra],
    ) -> Result<Self> {
        let (n, f) = dof_with(train, extras)?;
        let inputs = link_columns(train, inputs, f, "input links")?;
        let accelerated = link_columns(train, accelerated, f, "prescribed accelerations")?;
        let driving = link_columns(train, driving, f, "driving (unknown-torque) links")?;
        let Rows { circuits, extras } = Rows::new(train, extras);
        PreparedTrain {
            n,
            circuits,
            extras,
            accel_shared: inputs == accelerated,
            force_shared: accelerated == driving,
            inputs,
            accelerated,
            driving,
            mass: MassModel::empty(n),
            sparse: None,
            radii: train
                .gears()
                .iter()
                .map(|g| g.radii.map(|r| r[0]))
                .collect(),
        }
        .with_sparse(n >= PREPARED_SPARSE_FROM)
    }

    /// Number of coordinates (links but the frame).
    pub fn n(&self) -> usize {
        self.n
    }
    /// Number of constraint rows (Willis + extra).
    pub fn constraints(&self) -> usize {
        self.circuits.len() + self.extras.len()
    }
    /// Number of gear pairs.
    pub fn gears(&self) -> usize {
        self.circuits.len()
    }
    /// Degree of freedom left by the constraints (inputs, driving links).
    pub fn dof(&self) -> usize {
        self.inputs.len()
    }
    /// The mass model.
    pub fn mass_model(&self) -> &MassModel {
        &self.mass
    }
    /// Pitch radius of gear i of each gear pair, when known (for eq. 11).
    pub fn radii(&self) -> &[Option<f64>] {
        &self.radii
    }
    /// Whether the systems are factored sparsely and \[M\] held as terms
    /// (from [`PREPARED_SPARSE_FROM`] coordinates, unless set).
    pub fn is_sparse(&self) -> bool {
        self.sparse.is_some()
    }

    /// Factor sparsely (or densely) whatever the size: to compare the two
    /// on one train. Workspaces made before keep their kind.
    ///
    /// # Errors
    /// [`AnalysisError::OutOfMemory`] when faer cannot set up the analysis
    /// of a sparse pattern.
    pub fn with_sparse(mut self, sparse: bool) -> Result<Self> {
        self.sparse = if sparse {
            Some(self.sparse_factors()?)
        } else {
            None
        };
        Ok(self)
    }

    /// How many LU factorisations an ideal scenario costs (1 to 3).
    pub fn factorisations(&self) -> usize {
        1 + usize::from(!self.accel_shared) + usize::from(!self.force_shared)
    }

    /// The sparse LUs of the three systems, their patterns analysed.
    ///
    /// # Errors
    /// [`AnalysisError::OutOfMemory`] when faer cannot set up an analysis.
    fn sparse_factors(&self) -> Result<Box<[Factor; 3]>> {
        let g = self.circuits.len();
        let factor = |system: usize| -> Result<Factor> {
            let mut entries = Vec::new();
            self.for_each_entry(&vec![2.0; g], system, |r, c, _| entries.push((r, c)));
            let (lu, slots) =
                SparseLu::new(self.n, &entries).map_err(|e| AnalysisError::OutOfMemory {
                    what: "the sparse LU of the prepared train".into(),
                    detail: e.0,
                })?;
            Ok(Factor::Sparse(Box::new(lu), slots))
        };
        Ok(Box::new([factor(0)?, factor(1)?, factor(2)?]))
    }

    /// Buffers for one thread.
    pub fn workspace(&self) -> Workspace {
        let (n, g) = (self.n, self.circuits.len());
        let [kin, acc, force] = match &self.sparse {
            Some(f) => (**f).clone(),
            None => [
                Factor::Dense(Lu::new(n)),
                Factor::Dense(Lu::new(n)),
                Factor::Dense(Lu::new(n)),
            ],
        };
        Workspace {
            kin,
            acc,
            force,
            speed: vec![0.0; n],
            accel: vec![0.0; n],
            x: vec![0.0; n],
            m: if self.sparse.is_some() {
                Mass::Terms(Vec::with_capacity(n))
            } else {
                Mass::Dense(vec![0.0; n * n])
            },
            mw: vec![0.0; n],
            rhs: vec![0.0; n],
            tau: vec![0.0; g],
            rolling: vec![0.0; g],
            directions: Directions::new(g),
            cond: [1.0; 3],
            psi: None,
            psi_cond: 1.0,
            power: PowerSummary::default(),
            key: vec![f64::NAN; g],
            cache: Cache::default(),
        }
    }
}
