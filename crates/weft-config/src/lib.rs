//! weft's one configuration path: a preset (a typed struct with every default in code)
//! overlaid by a TOML file that names only what it changes.
//!
//! Every command that reads a config goes through [`overlay`], so the rules are the same
//! for models, training, data and the simulator:
//! - tables merge recursively, other values replace;
//! - a table whose `kind` differs from the preset's (a tagged enum such as an optimiser
//!   switched from `adamax` to `adam`) replaces the preset's table instead of merging
//!   into it, so the old variant's fields do not leak into the new one;
//! - a key the typed struct does not keep is refused, naming its dotted path and the file.
//!   The check is made on the result (deserialise, serialise again, look for every key
//!   of the file), so it holds for structs without `deny_unknown_fields`, such as burn's
//!   `Config` derive, and for `Option` fields the preset leaves unset.

use serde::{de::DeserializeOwned, Serialize};

/// What can go wrong reading or applying a config file.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// A key that the configuration does not have (a typo, or a key of another model).
    #[error("{origin}: unknown key `{key}`; expected one of: {}", expected.join(", "))]
    UnknownKey {
        /// The file (or other source) of the key.
        origin: String,
        /// Its dotted path, e.g. `model.feature_width`.
        key: String,
        /// The keys that table has.
        expected: Vec<String>,
    },
    /// A value of the wrong type or out of the type's range.
    #[error("{origin}: [{section}] does not fit the configuration: {message}")]
    Value {
        /// The file.
        origin: String,
        /// The table.
        section: String,
        /// The cause, naming the field, on one line.
        message: String,
    },
    /// The configuration could not be written as TOML (a value TOML cannot hold).
    #[error("the {what} configuration cannot be written as TOML")]
    Serialize {
        /// Which configuration.
        what: String,
        /// The cause.
        #[source]
        source: toml::ser::Error,
    },
}

/// Parses `text` as a TOML table; a syntax error is one line (see [`syntax_message`]).
pub fn parse_table(text: &str) -> Result<toml::Table, String> {
    toml::from_str(text).map_err(|e| syntax_message(text, &e))
}

/// A message of toml's on one line: its line breaks (``in `joints` `` on a line of its
/// own, a trailing newline) become `; `.
fn one_line(message: &str) -> String {
    message
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

/// A TOML error as one line, `line L, column C: message`. toml's own `Display` draws
/// the offending line and a caret over several lines, which breaks weft's rule of one
/// line per error (and repeats the user's file back at them).
pub fn syntax_message(text: &str, error: &toml::de::Error) -> String {
    let at = error.span().map(|span| {
        let before = &text[..span.start.min(text.len())];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before[line_start..].chars().count() + 1;
        format!("line {line}, column {column}: ")
    });
    format!("{}{}", at.unwrap_or_default(), one_line(error.message()))
}

/// `value` as a TOML table (`what` names it in errors).
pub fn to_table<T: Serialize>(what: &str, value: &T) -> Result<toml::Table, ConfigError> {
    toml::Table::try_from(value).map_err(|source| ConfigError::Serialize {
        what: what.to_string(),
        source,
    })
}

/// Refuses a top-level key of `table` that is not in `allowed` (e.g. `preset`,
/// `[model]`, `[train]`), naming it and `origin`.
pub fn check_keys(table: &toml::Table, allowed: &[&str], origin: &str) -> Result<(), ConfigError> {
    match table.keys().find(|k| !allowed.contains(&k.as_str())) {
        Some(key) => Err(ConfigError::UnknownKey {
            origin: origin.to_string(),
            key: key.clone(),
            expected: allowed.iter().map(|s| s.to_string()).collect(),
        }),
        None => Ok(()),
    }
}

/// `base` with `file` laid over it (see the crate documentation). `origin` names the
/// file and `section` the table (`model`, `train`, …) in errors and in dotted key paths;
/// an empty `section` means the file's top level.
pub fn overlay<T: Serialize + DeserializeOwned>(
    base: &T,
    file: &toml::Table,
    origin: &str,
    section: &str,
) -> Result<T, ConfigError> {
    let base = to_table(section, base)?;
    let mut merged = base.clone();
    merge(&mut merged, file);
    let unknown = |kept: &toml::Table| {
        find_unknown(file, kept, section).map(|(key, expected)| ConfigError::UnknownKey {
            origin: origin.to_string(),
            key,
            expected,
        })
    };
    let value: T = match toml::Value::Table(merged).try_into() {
        Ok(value) => value,
        // A struct that denies unknown fields fails here: name the key (dotted, as
        // below) rather than serde's bare field name.
        Err(source) => {
            let denied = source.to_string().contains("unknown field");
            return Err(unknown(&base)
                .filter(|_| denied)
                .unwrap_or_else(|| ConfigError::Value {
                    origin: origin.to_string(),
                    section: section.to_string(),
                    message: one_line(&source.to_string()),
                }));
        }
    };
    let kept = to_table(section, &value)?;
    unknown(&kept).map_or(Ok(value), Err)
}

/// `over` merged into `base`: tables recursively (unless their `kind` differs), other
/// values replaced.
fn merge(base: &mut toml::Table, over: &toml::Table) {
    for (k, v) in over {
        match (base.get_mut(k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) if same_kind(b, o) => merge(b, o),
            _ => {
                base.insert(k.clone(), v.clone());
            }
        }
    }
}

/// Whether `over` keeps the `kind` tag of `base` (or names none).
fn same_kind(base: &toml::Table, over: &toml::Table) -> bool {
    match over.get("kind") {
        Some(kind) => base.get("kind") == Some(kind),
        None => true,
    }
}

/// The first key of `file` (dotted, under `prefix`) that `kept` lacks, with the keys
/// `kept` has at that level.
fn find_unknown(
    file: &toml::Table,
    kept: &toml::Table,
    prefix: &str,
) -> Option<(String, Vec<String>)> {
    for (k, v) in file {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match (kept.get(k), v) {
            (None, _) => return Some((path, kept.keys().cloned().collect())),
            (Some(toml::Value::Table(kt)), toml::Value::Table(ft)) => {
                if let Some(found) = find_unknown(ft, kt, &path) {
                    return Some(found);
                }
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    /// One line, with the position, for a syntax error (issue 17 item 13).
    #[test]
    fn syntax_errors_are_one_line_with_the_position() {
        let e = super::parse_table("a = 1\nb = \n").unwrap_err();
        assert!(e.starts_with("line 2, column 5: "), "{e}");
        assert!(!e.contains('\n'), "{e}");
        assert!(super::parse_table("a = 1").is_ok());
    }

    use serde::Deserialize;

    use super::*;

    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(tag = "kind", rename_all = "lowercase")]
    enum Optim {
        Adam { beta1: f64 },
        Sgd { momentum: f64 },
    }

    // No deny_unknown_fields on purpose: the check must not rely on it.
    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default)]
    struct Cfg {
        width: usize,
        clip: Option<f64>,
        optim: Optim,
    }

    impl Default for Cfg {
        fn default() -> Self {
            Cfg {
                width: 32,
                clip: None,
                optim: Optim::Adam { beta1: 0.9 },
            }
        }
    }

    fn table(text: &str) -> toml::Table {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn overlays_only_what_the_file_names() {
        let c = overlay(&Cfg::default(), &table("clip = 1.5"), "f.toml", "train").unwrap();
        assert_eq!(c.width, 32);
        assert_eq!(c.clip, Some(1.5));
        let c = overlay(
            &Cfg::default(),
            &table("[optim]\nbeta1 = 0.5"),
            "f.toml",
            "train",
        )
        .unwrap();
        assert_eq!(c.optim, Optim::Adam { beta1: 0.5 });
    }

    #[test]
    fn a_new_kind_replaces_the_table() {
        let c = overlay(
            &Cfg::default(),
            &table("[optim]\nkind = \"sgd\"\nmomentum = 0.8"),
            "f.toml",
            "train",
        )
        .unwrap();
        assert_eq!(c.optim, Optim::Sgd { momentum: 0.8 });
    }

    #[test]
    fn unknown_keys_are_refused_at_any_depth_naming_them() {
        let e = overlay(&Cfg::default(), &table("widht = 64"), "f.toml", "model").unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("f.toml") && text.contains("`model.widht`"),
            "{text}"
        );
        assert!(text.contains("width"), "{text}");
        let e = overlay(
            &Cfg::default(),
            &table("[optim]\nbeta_1 = 0.5"),
            "f.toml",
            "train",
        )
        .unwrap_err();
        assert!(e.to_string().contains("`train.optim.beta_1`"), "{e}");
    }

    #[test]
    fn wrong_types_name_the_section() {
        let e = overlay(
            &Cfg::default(),
            &table("width = \"wide\""),
            "f.toml",
            "model",
        )
        .unwrap_err();
        assert!(matches!(e, ConfigError::Value { .. }), "{e:?}");
        assert!(e.to_string().contains("[model]"), "{e}");
        assert!(!e.to_string().contains('\n'), "{e}");
    }

    #[test]
    fn top_level_keys_are_checked() {
        let t = table("preset = \"cpu\"\n[modle]\nwidth = 3");
        let e = check_keys(&t, &["preset", "model", "train"], "f.toml").unwrap_err();
        assert!(e.to_string().contains("`modle`"), "{e}");
        check_keys(&table("preset = \"cpu\""), &["preset"], "f.toml").unwrap();
    }
}
