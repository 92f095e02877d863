//! The `[uncertainty]` table of a closed-loop `moma simulate` scenario. Its schema,
//! checks, seeded draw and application (`perturb`, `with_noise`) are
//! [`crate::sim::uncertainty`]'s, shared with `moma mission`; here, the contact plant's
//! draw of a scenario. Schema in `docs/simulate.md`.

use std::path::Path;

use super::{UNCERTAINTY_NEEDS_CONTROLLER, at, bail, chain};
use crate::error::{Error, Result};
use crate::sim::uncertainty::Draw;

/// The `[uncertainty]` draw of a `plant = "contact"` scenario (`None` without the
/// table), checked: the scenario must be closed loop.
///
/// # Errors
/// [`Error::Scenario`] naming the file and field.
pub fn contact_draw(sc: &super::Scenario, path: &Path) -> Result<Option<Draw>> {
    let Some(spec) = &sc.uncertainty else {
        return Ok(None);
    };
    spec.check()
        .map_err(|e| Error::Scenario(at(path, &chain(&e))))?;
    if sc.controller.is_none() {
        bail!("{}", at(path, UNCERTAINTY_NEEDS_CONTROLLER));
    }
    Ok(Some(spec.draw()))
}
