//! `--material`, `--pin` and `--buttons`: how every command that simulates cloth
//! (`simulate`, `bench simulate`, `garment prepare`, HOOD's `animate`) names the fabric,
//! the vertices held on the body and the vertex pairs buttoned together.

use anyhow::{bail, Context, Result};
use std::path::Path;
use weft_sim::Material;

/// `--material NAME|FILE.toml`: a preset by name, or a TOML file of [`Material`]'s
/// fields (`density`, `young_modulus`, `poisson_ratio`, `thickness`,
/// `bending_stiffness`, `friction`, optionally `name`) laid over HOOD's material, with
/// unknown keys refused naming the file and the key.
pub fn material(spec: &str) -> Result<Material> {
    let path = Path::new(spec);
    if !super::has_extension(path, &["toml"]) {
        return Material::preset(spec).context("--material");
    }
    let text = weft_mesh::io::read_input_to_string(path)
        .with_context(|| format!("--material {}", path.display()))?;
    let table = weft_config::parse_table(&text)
        .map_err(|message| anyhow::anyhow!("--material {}: {message}", path.display()))?;
    let base = Material {
        name: "custom",
        ..Material::hood()
    };
    let material = weft_config::overlay(&base, &table, &path.display().to_string(), "")?;
    material
        .validate()
        .with_context(|| format!("--material {}", path.display()))?;
    Ok(material)
}

/// `--pin LIST|FILE`: 0-based garment vertex indices as `0,5,17-30`, or a file of them
/// (`.txt`: indices and `a-b` ranges separated by commas, spaces or lines; `#` starts a
/// comment), in the order given.
pub fn pinned(spec: &str) -> Result<Vec<u32>> {
    let path = Path::new(spec);
    let (text, origin) = if path.exists() || super::has_extension(path, &["txt"]) {
        let text = weft_mesh::io::read_input_to_string(path)
            .with_context(|| format!("--pin {}", path.display()))?;
        (text, format!("--pin {}", path.display()))
    } else {
        (spec.to_owned(), "--pin".to_owned())
    };
    let mut out = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let content = line.split('#').next().unwrap_or("");
        for item in content
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|w| !w.is_empty())
        {
            let where_ = if origin == "--pin" {
                origin.clone()
            } else {
                format!("{origin}:{}", line_no + 1)
            };
            let index = |w: &str| {
                w.parse::<u32>().map_err(|_| {
                    anyhow::anyhow!(
                        "{where_}: `{item}` is not a vertex index; expected 0-based indices and ranges like 0,5,17-30"
                    )
                })
            };
            match item.split_once('-') {
                Some((a, b)) => {
                    let (a, b) = (index(a)?, index(b)?);
                    if a > b {
                        bail!("{where_}: range `{item}` runs backwards; expected a-b with a <= b");
                    }
                    out.extend(a..=b);
                }
                None => out.push(index(item)?),
            }
        }
    }
    if out.is_empty() {
        bail!("{origin}: no vertex indices; expected 0-based indices and ranges like 0,5,17-30");
    }
    Ok(out)
}

/// `--buttons PAIRS.json`: a JSON list of 0-based garment vertex pairs `[[a, b], ...]`.
pub fn buttons(path: &std::path::Path) -> Result<Vec<[u32; 2]>> {
    let text = weft_mesh::io::read_input_to_string(path)
        .with_context(|| format!("--buttons {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| {
        format!(
            "--buttons {}: expected a JSON list of vertex pairs like [[12, 340], [15, 352]]",
            path.display()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pins_parse_lists_ranges_and_refuse_nonsense() {
        assert_eq!(pinned("0,5,7-9").unwrap(), vec![0, 5, 7, 8, 9]);
        assert_eq!(pinned("3").unwrap(), vec![3]);
        let e = pinned("1,x").unwrap_err().to_string();
        assert_eq!(
            e,
            "--pin: `x` is not a vertex index; expected 0-based indices and ranges like 0,5,17-30"
        );
        let e = pinned("9-2").unwrap_err().to_string();
        assert!(e.contains("runs backwards"), "{e}");
        assert!(pinned(",").is_err() && pinned("-1").is_err());
    }
}
