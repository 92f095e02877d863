//! The one registry of the chapter's models: their canonical names (as in the reference
//! files), the aliases users may type, and the lookup that `moma eval` (case files) and
//! `moma simulate` (scenarios, through [`crate::sim::chapter_models::chapter_system`])
//! both use, so the two commands accept the same names.

use crate::error::{Error, Result};

/// The chapter's models.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChapterModel {
    /// m1, the unicycle platform.
    M1Unicycle,
    /// m2, platform + horizontal two-link arm.
    M2PlatformArm,
    /// m3, wheel-rate kinematics and whole-body Jacobian.
    M3DiffDrive,
    /// m4, cart + vertical two-link arm.
    M4CartTwoLink,
    /// m5, 3-D mobile manipulator.
    M5MobileManipulator,
    /// m6, planar free-floating space manipulator.
    M6SpaceManipulator,
}

/// Canonical model names (as in the reference files) with accepted aliases; the first
/// alias is the short name (`m1` … `m6`).
pub const MODEL_NAMES: [(&str, &[&str], ChapterModel); 6] = [
    ("m1_unicycle", &["m1"], ChapterModel::M1Unicycle),
    (
        "m2_platform_planar_arm",
        &["m2", "m2_platform_arm"],
        ChapterModel::M2PlatformArm,
    ),
    (
        "m3_diffdrive_kinematics",
        &["m3", "m3_diffdrive"],
        ChapterModel::M3DiffDrive,
    ),
    ("m4_cart_two_link", &["m4"], ChapterModel::M4CartTwoLink),
    (
        "m5_mobile_manipulator_3d",
        &["m5", "m5_mobile_manipulator"],
        ChapterModel::M5MobileManipulator,
    ),
    (
        "m6_space_manipulator",
        &["m6", "m6_space"],
        ChapterModel::M6SpaceManipulator,
    ),
];

impl ChapterModel {
    /// Looks a model up by its canonical name or alias.
    pub fn from_name(name: &str) -> Result<Self> {
        for (canon, aliases, m) in MODEL_NAMES {
            if name == canon || aliases.contains(&name) {
                return Ok(m);
            }
        }
        let known: Vec<&str> = MODEL_NAMES.iter().map(|(c, _, _)| *c).collect();
        Err(Error::invalid(
            "model",
            format!("unknown model '{name}'; known models: {}", known.join(", ")),
        ))
    }

    fn entry(self) -> &'static (&'static str, &'static [&'static str], ChapterModel) {
        MODEL_NAMES
            .iter()
            .find(|(_, _, m)| *m == self)
            .expect("every model has a row in MODEL_NAMES")
    }

    /// The canonical name, as in the reference files (e.g. `m1_unicycle`).
    #[must_use]
    pub fn canonical_name(self) -> &'static str {
        self.entry().0
    }

    /// The short name (`m1` … `m6`).
    #[must_use]
    pub fn short_name(self) -> &'static str {
        self.entry().1[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_and_alias_resolves_to_its_model() {
        for (canon, aliases, m) in MODEL_NAMES {
            assert_eq!(ChapterModel::from_name(canon).unwrap(), m);
            assert_eq!(m.canonical_name(), canon);
            for a in aliases {
                assert_eq!(ChapterModel::from_name(a).unwrap(), m);
            }
            assert_eq!(m.short_name(), aliases[0]);
        }
        let err = ChapterModel::from_name("m7").unwrap_err().to_string();
        assert!(err.contains("unknown model 'm7'"), "{err}");
        assert!(err.contains("m5_mobile_manipulator_3d"), "{err}");
    }
}
