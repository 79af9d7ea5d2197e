//! Writing garments as Wavefront OBJ with `vt` texture coordinates.
//!
//! weft-mesh's OBJ writer has no UVs, so garments are written here: `v` lines, one `vt`
//! per distinct corner UV (metres; OBJ readers take any range), and `f v/vt` faces. The
//! file is written atomically through weft-mesh, so a failure never leaves half a file.
//! weft-mesh's reader ignores `vt`, so the positions and faces read back unchanged.

use std::collections::HashMap;
use std::io::{self, Write};
use std::path::Path;

use crate::{Garment, GarmentError};

/// Writes `garment` to `w` as OBJ text.
pub fn write_obj_to(w: &mut dyn Write, garment: &Garment) -> io::Result<()> {
    writeln!(w, "# weft garment: {}", garment.kind.name())?;
    writeln!(
        w,
        "# {} vertices, {} faces; vt are UVs in metres",
        garment.mesh.vertex_count(),
        garment.mesh.face_count()
    )?;
    for p in &garment.mesh.positions {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    let mut index: HashMap<[u64; 2], usize> = HashMap::new();
    let mut corners = Vec::with_capacity(garment.corner_uvs.len());
    for uv in &garment.corner_uvs {
        let mut f = [0usize; 3];
        for (c, t) in uv.iter().enumerate() {
            let key = [t[0].to_bits(), t[1].to_bits()];
            let next = index.len();
            let i = *index.entry(key).or_insert_with(|| next);
            if i == next {
                writeln!(w, "vt {} {}", t[0], t[1])?;
            }
            f[c] = i;
        }
        corners.push(f);
    }
    for (face, t) in garment.mesh.faces.iter().zip(&corners) {
        writeln!(
            w,
            "f {}/{} {}/{} {}/{}",
            face[0] + 1,
            t[0] + 1,
            face[1] + 1,
            t[1] + 1,
            face[2] + 1,
            t[2] + 1
        )?;
    }
    Ok(())
}

/// Writes `garment` to `path` atomically.
pub fn write_obj(path: &Path, garment: &Garment) -> Result<(), GarmentError> {
    weft_mesh::io::write_atomic(path, |w| write_obj_to(w, garment)).map_err(|source| {
        GarmentError::Io {
            path: path.display().to_string(),
            source,
        }
    })
}
