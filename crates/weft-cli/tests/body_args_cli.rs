//! `--body/--betas`, the one body argument type of every command that takes a body:
//! negative β parse (`--betas -1,2`), and more β than the body has are refused naming
//! the flag and the limit, whichever command reads them.

mod common;
use common::{s, scratch, stderr, stdout, weft};

/// One β more than the default body's 10.
const ELEVEN: &str = "0,0,0,0,0,0,0,0,0,0,1";

#[test]
fn negative_betas_are_accepted() {
    let dir = scratch("negative");
    let obj = dir.join("body.obj");
    let o = weft(&["body", "export", "--betas", "-1,2", "--out", s(&obj)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("β = [-1, 2]"), "{}", stdout(&o));
    assert!(obj.is_file());
    // The BVH skeleton follows J(β): β = (-1, 2) gives other offsets than β = 0.
    let bvh = |name: &str, betas: &[&str]| {
        let out = dir.join(name);
        let mut args = vec!["motion", "generate", "--kind", "walk", "--frames", "3"];
        args.extend_from_slice(betas);
        args.extend_from_slice(&["--out", s(&out)]);
        let o = weft(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        std::fs::read_to_string(&out).unwrap()
    };
    assert_ne!(
        bvh("shaped.bvh", &["--betas", "-1,2"]),
        bvh("rest.bvh", &[])
    );
    let png = dir.join("body.png");
    let o = weft(&[
        "render",
        s(&obj),
        "--default-body",
        "--betas",
        "-1,2",
        "--size",
        "64",
        "--out",
        s(&png),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("over the default body"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn too_many_betas_name_the_flag_and_the_limit() {
    let dir = scratch("too_many");
    let out = dir.join("never");
    let never = s(&out);
    let motion_out = dir.join("never.npz");
    let never_npz = s(&motion_out);
    let cases: [(Vec<&str>, &str); 4] = [
        (
            vec!["body", "export", "--betas", ELEVEN, "--out", never],
            "--betas",
        ),
        (
            vec![
                "motion", "generate", "--kind", "walk", "--betas", ELEVEN, "--out", never_npz,
            ],
            "--betas",
        ),
        (
            vec![
                "garment", "generate", "--kind", "skirt", "--betas", ELEVEN, "--out", never,
            ],
            "--betas",
        ),
        (
            vec![
                "garment",
                "resize",
                "--garment",
                never,
                "--to-betas",
                ELEVEN,
                "--out",
                never,
            ],
            "--to-betas",
        ),
    ];
    for (args, flag) in cases {
        let o = weft(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains(flag) && e.contains("11 shape coefficients") && e.contains("at most 10"),
            "{args:?}: {e}"
        );
        assert_eq!(e.lines().count(), 1, "{e}");
        assert!(!out.exists() && !motion_out.exists());
    }
}

/// Issue 17 item 6: β beyond ±5 (a 3.9 m body at 100, vertices at 1e306 m for 1e308)
/// is refused naming the flag and the way out; `--allow-extreme-shapes` takes it.
#[test]
fn extreme_betas_are_refused_unless_allowed() {
    let dir = scratch("extreme");
    let out = dir.join("never.obj");
    for (betas, flag) in [
        ("100", "--betas"),
        ("0,1e308", "--betas"),
        ("-6", "--betas"),
    ] {
        let o = weft(&["body", "export", flag, betas, "--out", s(&out)]);
        assert_eq!(o.status.code(), Some(1), "{betas}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains("--betas: β")
                && e.contains("outside ±5")
                && e.contains("--allow-extreme-shapes"),
            "{e}"
        );
        assert_eq!(e.lines().count(), 1, "{e}");
        assert!(!out.exists());
    }
    let o = weft(&[
        "garment",
        "resize",
        "--garment",
        s(&out),
        "--to-betas",
        "0,7",
        "--out",
        s(&out),
    ]);
    assert!(
        stderr(&o).contains("--to-betas: β2 = 7 is outside ±5"),
        "{}",
        stderr(&o)
    );
    let o = weft(&[
        "body",
        "export",
        "--betas",
        "6",
        "--allow-extreme-shapes",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.is_file());
}

/// Issue 17 item 13: a negative number given to an option that takes none is refused
/// naming the option (clap said "unexpected argument '-5' found"), in one line.
#[test]
fn negative_numbers_name_their_option() {
    let dir = scratch("negative_flags");
    let out = dir.join("never.npz");
    let cases: [(Vec<&str>, &str); 4] = [
        (
            vec![
                "motion",
                "generate",
                "--kind",
                "walk",
                "--fps",
                "-3",
                "--out",
                s(&out),
            ],
            "--fps",
        ),
        (
            vec![
                "motion",
                "generate",
                "--kind",
                "walk",
                "--frames",
                "-5",
                "--out",
                s(&out),
            ],
            "--frames",
        ),
        (
            vec![
                "garment",
                "generate",
                "--kind",
                "skirt",
                "--vertices",
                "-100",
                "--out",
                s(&out),
            ],
            "--vertices",
        ),
        (
            vec![
                "simulate",
                "--garment",
                s(&out),
                "--motion",
                "walk",
                "--substeps",
                "-1",
                "--out",
                s(&out),
            ],
            "--substeps",
        ),
    ];
    for (args, flag) in cases {
        let o = weft(&args);
        let e = stderr(&o);
        assert!(!o.status.success(), "{args:?}");
        assert!(
            e.starts_with("error: ") && e.contains(flag),
            "{args:?}: {e}"
        );
        assert!(!e.contains("unexpected argument"), "{args:?}: {e}");
        assert_eq!(e.trim_end().lines().count(), 1, "{args:?}: {e}");
        assert!(!out.exists());
    }
}
