//! Joint-name maps: which BVH joint drives which SMPL joint.
//!
//! Built-in maps cover the skeletons motion files usually come with — SMPL's own names,
//! the CMU motion-capture database (both the ASF-derived names such as `lfemur` and the
//! widely used BVH conversion with `LeftUpLeg`), Mixamo (`mixamorig:` prefix) and
//! MakeHuman/MPFB (`upperleg01.L`). A user map (TOML or JSON, BVH name → SMPL name)
//! covers anything else.
//!
//! Names are compared after [`normalize_joint_name`]: case-insensitively and without a
//! namespace prefix (anything up to the last `:` or `|`), because exporters add
//! `mixamorig:`, `mixamorig1:` or `Armature|` at will. BVH joints a map does not name
//! are simply not used; several source joints between two mapped ones (CMU's `Neck1`,
//! MPFB's five spine bones) still count, because retargeting works on global rotations.

use std::collections::HashMap;
use std::path::Path;

use super::error::MotionError;
use weft_body::joints::{smpl_joint_index, SMPL_JOINT_NAMES};

/// The key a joint name is looked up by: lower case, without a namespace prefix.
///
/// ```
/// use weft_motion::normalize_joint_name;
/// assert_eq!(normalize_joint_name("mixamorig:LeftUpLeg"), "leftupleg");
/// assert_eq!(normalize_joint_name("Armature|upperleg01.L"), "upperleg01.l");
/// ```
pub fn normalize_joint_name(name: &str) -> String {
    let base = name.rsplit([':', '|']).next().unwrap_or(name);
    base.trim().to_lowercase()
}

/// The skeletons weft ships a name map for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SkeletonPreset {
    /// SMPL's joint names (what weft writes), also the `L_Hip`/`Pelvis` spelling of the
    /// SMPL Blender add-on and `smplx`.
    Smpl,
    /// Mixamo rigs (`mixamorig:Hips`, `Spine`, `Spine1`, `Spine2`, `LeftUpLeg` …).
    Mixamo,
    /// The CMU motion-capture database: the common BVH conversion (`Hips`, `LowerBack`,
    /// `Spine`, `Spine1`, `LeftUpLeg` …) and the original ASF names (`lfemur`, `ltibia` …).
    Cmu,
    /// MakeHuman / MPFB2 default rig (`root`, `spine05`…`spine01`, `upperleg01.L` …).
    Mpfb,
}

impl SkeletonPreset {
    /// Every preset, in the order auto-detection breaks ties.
    pub const ALL: [SkeletonPreset; 4] = [
        SkeletonPreset::Smpl,
        SkeletonPreset::Mixamo,
        SkeletonPreset::Cmu,
        SkeletonPreset::Mpfb,
    ];

    /// The preset's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            SkeletonPreset::Smpl => "smpl",
            SkeletonPreset::Mixamo => "mixamo",
            SkeletonPreset::Cmu => "cmu",
            SkeletonPreset::Mpfb => "mpfb",
        }
    }

    /// The preset called `name` (any case).
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL
            .into_iter()
            .find(|p| p.name().eq_ignore_ascii_case(name))
    }

    /// `(source name, SMPL joint name)` pairs; several source names may alias one SMPL
    /// joint when no file holds both (CMU's two naming schemes).
    fn pairs(self) -> Vec<(String, &'static str)> {
        match self {
            SkeletonPreset::Smpl => {
                let mut v: Vec<(String, &str)> = SMPL_JOINT_NAMES
                    .iter()
                    .map(|&n| (n.to_owned(), n))
                    .collect();
                for (alias, smpl) in SMPL_ADDON {
                    v.push(((*alias).to_owned(), smpl));
                }
                v
            }
            SkeletonPreset::Mixamo => sided(MIXAMO),
            SkeletonPreset::Cmu => sided(CMU),
            SkeletonPreset::Mpfb => sided(MPFB),
        }
    }
}

/// Spellings of the SMPL Blender add-on and `smplx` (`L_Hip`, `Spine1`, `L_Collar` …).
const SMPL_ADDON: &[(&str, &str)] = &[
    ("Pelvis", "pelvis"),
    ("L_Hip", "left_hip"),
    ("R_Hip", "right_hip"),
    ("L_Knee", "left_knee"),
    ("R_Knee", "right_knee"),
    ("Spine2", "spine2"),
    ("L_Ankle", "left_ankle"),
    ("R_Ankle", "right_ankle"),
    ("Spine3", "spine3"),
    ("L_Foot", "left_foot"),
    ("R_Foot", "right_foot"),
    ("Neck", "neck"),
    ("L_Collar", "left_collar"),
    ("R_Collar", "right_collar"),
    ("Head", "head"),
    ("L_Shoulder", "left_shoulder"),
    ("R_Shoulder", "right_shoulder"),
    ("L_Elbow", "left_elbow"),
    ("R_Elbow", "right_elbow"),
    ("L_Wrist", "left_wrist"),
    ("R_Wrist", "right_wrist"),
    ("L_Hand", "left_hand"),
    ("R_Hand", "right_hand"),
];

/// A map entry written once for both sides: `{S}` is replaced by the side's spelling
/// (`Left`/`Right`, `l`/`r`, `L`/`R`) and `{s}` of the SMPL name by `left`/`right`.
type Sided = (&'static str, &'static str);

/// Mixamo: three spine bones, `LeftShoulder` is the clavicle, `LeftArm` the upper arm,
/// the hand joint taken at the middle finger's base (SMPL's hand joint sits at the
/// knuckles).
const MIXAMO: &[Sided] = &[
    ("Hips", "pelvis"),
    ("Spine", "spine1"),
    ("Spine1", "spine2"),
    ("Spine2", "spine3"),
    ("Neck", "neck"),
    ("Head", "head"),
    ("{Side}UpLeg", "{s}_hip"),
    ("{Side}Leg", "{s}_knee"),
    ("{Side}Foot", "{s}_ankle"),
    ("{Side}ToeBase", "{s}_foot"),
    ("{Side}Shoulder", "{s}_collar"),
    ("{Side}Arm", "{s}_shoulder"),
    ("{Side}ForeArm", "{s}_elbow"),
    ("{Side}Hand", "{s}_wrist"),
    ("{Side}HandMiddle1", "{s}_hand"),
];

/// CMU: the BVH conversion (`LowerBack`, `Spine`, `Spine1`; `LHipJoint` and `Neck1`
/// are in-between joints left unmapped) and the ASF names of the original database.
const CMU: &[Sided] = &[
    ("Hips", "pelvis"),
    ("LowerBack", "spine1"),
    ("Spine", "spine2"),
    ("Spine1", "spine3"),
    ("Neck", "neck"),
    ("Head", "head"),
    ("{Side}UpLeg", "{s}_hip"),
    ("{Side}Leg", "{s}_knee"),
    ("{Side}Foot", "{s}_ankle"),
    ("{Side}ToeBase", "{s}_foot"),
    ("{Side}Shoulder", "{s}_collar"),
    ("{Side}Arm", "{s}_shoulder"),
    ("{Side}ForeArm", "{s}_elbow"),
    ("{Side}Hand", "{s}_wrist"),
    ("{Side}FingerBase", "{s}_hand"),
    // ASF names of the original database.
    ("hip", "pelvis"),
    ("lowerback", "spine1"),
    ("upperback", "spine2"),
    ("thorax", "spine3"),
    ("lowerneck", "neck"),
    ("{l}femur", "{s}_hip"),
    ("{l}tibia", "{s}_knee"),
    ("{l}foot", "{s}_ankle"),
    ("{l}toes", "{s}_foot"),
    ("{l}clavicle", "{s}_collar"),
    ("{l}humerus", "{s}_shoulder"),
    ("{l}radius", "{s}_elbow"),
    ("{l}wrist", "{s}_wrist"),
    ("{l}hand", "{s}_hand"),
];

/// MakeHuman / MPFB2 default rig: five spine bones (`spine05` lowest), three neck bones,
/// two segments per limb bone (the first carries the joint), toes and fingers split.
const MPFB: &[Sided] = &[
    ("root", "pelvis"),
    ("spine05", "spine1"),
    ("spine03", "spine2"),
    ("spine01", "spine3"),
    ("neck01", "neck"),
    ("head", "head"),
    ("upperleg01.{L}", "{s}_hip"),
    ("lowerleg01.{L}", "{s}_knee"),
    ("foot.{L}", "{s}_ankle"),
    ("toe3-1.{L}", "{s}_foot"),
    ("clavicle.{L}", "{s}_collar"),
    ("upperarm01.{L}", "{s}_shoulder"),
    ("lowerarm01.{L}", "{s}_elbow"),
    ("wrist.{L}", "{s}_wrist"),
    ("finger3-1.{L}", "{s}_hand"),
];

/// Expands sided entries into both sides.
fn sided(table: &[Sided]) -> Vec<(String, &'static str)> {
    let mut out = Vec::new();
    for &(source, smpl) in table {
        if !smpl.contains("{s}") {
            out.push((source.to_owned(), smpl));
            continue;
        }
        for (side, long, short, upper) in [("left", "Left", "l", "L"), ("right", "Right", "r", "R")]
        {
            let src = source
                .replace("{Side}", long)
                .replace("{l}", short)
                .replace("{L}", upper);
            let name = smpl.replace("{s}", side);
            // Every sided SMPL name exists; the fallback is unreachable.
            let static_name = SMPL_JOINT_NAMES
                .iter()
                .find(|&&n| n == name)
                .copied()
                .unwrap_or("pelvis");
            out.push((src, static_name));
        }
    }
    out
}

/// A map from BVH joint names (compared after [`normalize_joint_name`]) to SMPL joint
/// indices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NameMap {
    label: String,
    /// `(normalized source name, source name as given, SMPL index)`.
    entries: Vec<(String, String, usize)>,
    /// Normalized source name → its first entry, so a lookup is one hash, not a scan
    /// (a BVH file of many joints against a large map file would otherwise be
    /// quadratic).
    index: HashMap<String, usize>,
}

impl NameMap {
    /// The built-in map of a preset.
    pub fn preset(preset: SkeletonPreset) -> NameMap {
        let entries = preset
            .pairs()
            .into_iter()
            .filter_map(|(src, smpl)| {
                smpl_joint_index(smpl).map(|j| (normalize_joint_name(&src), src, j))
            })
            .collect();
        NameMap::with_entries(preset.name(), entries)
    }

    fn with_entries(label: &str, entries: Vec<(String, String, usize)>) -> NameMap {
        let mut index = HashMap::with_capacity(entries.len());
        for (i, e) in entries.iter().enumerate() {
            index.entry(e.0.clone()).or_insert(i);
        }
        NameMap {
            label: label.to_owned(),
            entries,
            index,
        }
    }

    /// A map from `(BVH name, SMPL name)` pairs. Fails naming the pair when an SMPL
    /// name is not one of [`SMPL_JOINT_NAMES`] or one source name is given two targets.
    pub fn from_pairs<I, A, B>(label: &str, pairs: I) -> Result<NameMap, String>
    where
        I: IntoIterator<Item = (A, B)>,
        A: AsRef<str>,
        B: AsRef<str>,
    {
        let mut entries: Vec<(String, String, usize)> = Vec::new();
        let mut seen: HashMap<String, usize> = HashMap::new();
        for (src, smpl) in pairs {
            let (src, smpl) = (src.as_ref(), smpl.as_ref());
            let j = smpl_joint_index(smpl).ok_or_else(|| {
                format!(
                    "'{src}' maps to '{smpl}', which is no SMPL joint; expected one of {}",
                    SMPL_JOINT_NAMES.join(", ")
                )
            })?;
            let key = normalize_joint_name(src);
            if let Some((_, other, k)) = seen.get(&key).map(|&i| &entries[i]) {
                if *k != j {
                    return Err(format!(
                        "'{src}' and '{other}' name the same joint (names compare without case and namespace prefix) but map to '{}' and '{smpl}'",
                        SMPL_JOINT_NAMES[*k]
                    ));
                }
                continue;
            }
            seen.insert(key.clone(), entries.len());
            entries.push((key, src.to_owned(), j));
        }
        if entries.is_empty() {
            return Err("the map is empty; expected entries like Hips = \"pelvis\"".into());
        }
        Ok(NameMap::with_entries(label, entries))
    }

    /// Reads a map file: TOML (`.toml`, `Hips = "pelvis"` per line, quote names with
    /// `:` or `.`) or JSON (`.json`, `{"Hips": "pelvis", …}`).
    pub fn read(path: &Path) -> Result<NameMap, MotionError> {
        let err = |message: String| MotionError::NameMap {
            path: path.to_path_buf(),
            message,
        };
        let text =
            weft_mesh::io::read_input_to_string(path).map_err(|e| MotionError::io(path, e))?;
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let pairs: Vec<(String, String)> = match ext.as_deref() {
            Some("toml") => {
                let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
                    err(format!("not valid TOML: {}", e.message()))
                })?;
                table
                    .into_iter()
                    .map(|(k, v)| match v {
                        toml::Value::String(s) => Ok((k, s)),
                        other => Err(err(format!(
                            "'{k}' maps to {other}; expected an SMPL joint name in quotes"
                        ))),
                    })
                    .collect::<Result<_, _>>()?
            }
            Some("json") => {
                let value: serde_json::Value =
                    serde_json::from_str(&text).map_err(|e| err(format!("not valid JSON: {e}")))?;
                let serde_json::Value::Object(object) = value else {
                    return Err(err(
                        "expected one JSON object of BVH name → SMPL name".into()
                    ));
                };
                object
                    .into_iter()
                    .map(|(k, v)| match v {
                        serde_json::Value::String(s) => Ok((k, s)),
                        other => Err(err(format!(
                            "'{k}' maps to {other}; expected an SMPL joint name string"
                        ))),
                    })
                    .collect::<Result<_, _>>()?
            }
            _ => {
                return Err(err(
                    "unknown map format; expected a .toml or .json file".into()
                ))
            }
        };
        NameMap::from_pairs(&path.display().to_string(), pairs).map_err(err)
    }

    /// Where the map came from: a preset's name or the map file's path.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The SMPL joint a BVH joint name maps to.
    pub fn lookup(&self, bvh_name: &str) -> Option<usize> {
        let key = normalize_joint_name(bvh_name);
        self.index.get(&key).map(|&i| self.entries[i].2)
    }

    /// The source names the map knows for SMPL joint `smpl`, for messages.
    pub fn sources_of(&self, smpl: usize) -> Vec<&str> {
        self.entries
            .iter()
            .filter(|e| e.2 == smpl)
            .map(|e| e.1.as_str())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_cover_every_smpl_joint() {
        for p in SkeletonPreset::ALL {
            let m = NameMap::preset(p);
            for (j, name) in SMPL_JOINT_NAMES.iter().enumerate() {
                assert!(!m.sources_of(j).is_empty(), "{} lacks {name}", p.name());
            }
            assert_eq!(SkeletonPreset::parse(&p.name().to_uppercase()), Some(p));
        }
    }

    #[test]
    fn lookups_ignore_case_and_namespace() {
        let mixamo = NameMap::preset(SkeletonPreset::Mixamo);
        assert_eq!(
            mixamo.lookup("mixamorig:LeftForeArm"),
            smpl_joint_index("left_elbow")
        );
        assert_eq!(
            mixamo.lookup("mixamorig1:Spine2"),
            smpl_joint_index("spine3")
        );
        let cmu = NameMap::preset(SkeletonPreset::Cmu);
        assert_eq!(cmu.lookup("Spine1"), smpl_joint_index("spine3"));
        assert_eq!(cmu.lookup("rhumerus"), smpl_joint_index("right_shoulder"));
        assert_eq!(cmu.lookup("LHipJoint"), None);
        let mpfb = NameMap::preset(SkeletonPreset::Mpfb);
        assert_eq!(mpfb.lookup("upperleg01.R"), smpl_joint_index("right_hip"));
        assert_eq!(mpfb.lookup("upperleg02.R"), None);
        let smpl = NameMap::preset(SkeletonPreset::Smpl);
        assert_eq!(smpl.lookup("L_Wrist"), smpl_joint_index("left_wrist"));
        assert_eq!(smpl.lookup("right_hand"), Some(23));
    }

    #[test]
    fn user_pairs_are_checked() {
        let m = NameMap::from_pairs("t", [("Bip01 Pelvis", "pelvis"), ("Thigh_L", "left_hip")])
            .unwrap();
        assert_eq!(m.lookup("thigh_l"), Some(1));
        let e = NameMap::from_pairs("t", [("Hips", "hips")]).unwrap_err();
        assert!(
            e.contains("'Hips' maps to 'hips', which is no SMPL joint"),
            "{e}"
        );
        let e = NameMap::from_pairs("t", [("a:Hips", "pelvis"), ("Hips", "spine1")]).unwrap_err();
        assert!(e.contains("name the same joint"), "{e}");
        assert!(NameMap::from_pairs::<_, &str, &str>("t", []).is_err());
    }
}
