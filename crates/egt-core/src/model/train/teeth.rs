//! Gear ratios from tooth counts and mesh kinds, and the checks of a spec's
//! numbers (finite, positive, bounded, tooth counts).

use super::*;

pub(crate) fn missing_ratio(g: &GearPair, analysis: &str) -> Error {
    crate::AnalysisError::MissingData {
        what: format!("the ratio of gear pair `{}`", g.name),
        analysis: analysis.to_string(),
        hint: format!("give `teeth` and `mesh`, or `ratio`, at {}", g.path),
    }
    .into()
}

pub(super) fn finite(path: String, v: f64) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::spec(path, SpecErrorKind::NonFinite { value: v }))
    }
}

pub(super) fn positive(path: String, v: f64) -> Result<f64> {
    bounded(path, v, v > 0.0, "must be > 0")
}

pub(super) fn non_negative(path: String, v: f64) -> Result<f64> {
    bounded(path, v, v >= 0.0, "must be >= 0")
}

/// `v`, finite and within the bound `ok` (else an out-of-range error saying `expected`).
fn bounded(path: String, v: f64, ok: bool, expected: &str) -> Result<f64> {
    let v = finite(path.clone(), v)?;
    if ok {
        Ok(v)
    } else {
        Err(Error::spec(
            path,
            SpecErrorKind::OutOfRange {
                value: v,
                expected: expected.into(),
            },
        ))
    }
}

pub(super) fn teeth_value(path: String, z: i64) -> Result<u32> {
    u32::try_from(z)
        .ok()
        .filter(|&z| z > 0 && i64::from(z) <= crate::error::MAX_TEETH)
        .ok_or_else(|| Error::spec(path, SpecErrorKind::InvalidTeeth { value: z }))
}

impl Train {
    /// The mesh kind ratios from tooth counts use for gear pair `g`: as
    /// given, else the kind the sign of its given ratio implies (negative:
    /// external); None when neither is known.
    pub fn mesh_kind(&self, g: GearId) -> Option<MeshKind> {
        let gear = &self.gears()[g.index()];
        gear.mesh.or_else(|| {
            gear.ratio.as_ref().map(|r| {
                if r.value < 0.0 {
                    MeshKind::External
                } else {
                    MeshKind::Internal
                }
            })
        })
    }

    /// The ratios of every gear pair from one set of tooth counts
    /// (`teeth[m] = [z_i, z_j]` in gear-pair order) into `out`, by
    /// [`ratio_from_teeth`]; `row` names the set in errors (a batch row).
    ///
    /// # Errors
    /// Wrong counts of pairs; a pair without a known mesh kind; bad tooth
    /// counts, named by row and gear pair.
    pub fn ratios_from_teeth(&self, row: &str, teeth: &[[i64; 2]], out: &mut [f64]) -> Result<()> {
        let n = self.gears().len();
        if teeth.len() != n || out.len() != n {
            return Err(Error::invalid(
                row,
                format!(
                    "tooth counts for {n} gear pairs are needed, got {}",
                    teeth.len()
                ),
            ));
        }
        for (m, (z, o)) in teeth.iter().zip(out.iter_mut()).enumerate() {
            let name = &self.gears()[m].name;
            let path = format!("{row}[{m}] (gear pair `{name}`)");
            let mesh = self.mesh_kind(GearId::from_index(m)).ok_or_else(|| {
                Error::spec(
                    format!("gear pair `{name}`.mesh"),
                    SpecErrorKind::Missing {
                        what:
                            "the mesh kind (`external` or `internal`) that ratios from teeth need"
                                .into(),
                    },
                )
            })?;
            *o = exact::to_f64(&ratio_from_teeth(&path, mesh, *z)?);
        }
        Ok(())
    }
}

/// The Willis ratio of a gear pair from its tooth counts `[z_i, z_j]`:
/// tau = -z_j / z_i for an external mesh, +z_j / z_i for an internal one
/// (eq. 2), exactly. The one rule for specs and for batches of tooth counts;
/// `path` names the counts in errors.
///
/// # Errors
/// A count that is not a positive integer up to [`crate::error::MAX_TEETH`];
/// equal counts on an internal mesh (tau = 1 would lock the pair).
pub fn ratio_from_teeth(path: &str, mesh: MeshKind, teeth: [i64; 2]) -> Result<Q> {
    let zi = teeth_value(format!("{path}[0]"), teeth[0])?;
    let zj = teeth_value(format!("{path}[1]"), teeth[1])?;
    if mesh == MeshKind::Internal && zi == zj {
        return Err(Error::invalid(
            path,
            "an internal mesh needs different tooth counts (tau = 1 would lock the pair)",
        ));
    }
    let tau = exact::frac(i64::from(zj), i64::from(zi));
    Ok(if mesh == MeshKind::External {
        -tau
    } else {
        tau
    })
}
