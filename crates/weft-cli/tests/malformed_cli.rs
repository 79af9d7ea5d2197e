//! The malformed-input corpus of `tests/malformed/` (every file is described in its
//! README.md) and bad command-line arguments, run through every command that reads them.
//!
//! Each case must fail the way a user can act on: a non-zero exit status, no panic,
//! exactly one line on stderr that starts with `error: ` and names the offending file (its
//! file name) or flag (`--name`) and says what is wrong with it, nothing on stdout, and
//! nothing left behind: the case's scratch directory (the working directory of the
//! command and the place of every output path) holds afterwards exactly what it held
//! before, and neither the corpus nor the shared fixtures change.
//!
//! A case is a command line with placeholders: `{m}` the corpus directory, `{f}` the
//! fixtures (valid inputs made once: `triangle.obj`, `frames.npy` of 2 frames × 3 vertices,
//! `garment.obj`, `walk.npz`, `walk.bvh`), `{s}` the case's own scratch directory, which
//! starts out holding `a_file.obj` (a file where a directory is expected) and `a_dir/`
//! (a directory where a file is expected), and `{in}` the corpus file of a table row.
//!
//! Cases that weft gets wrong today are listed in [`KNOWN`] with what goes wrong; they are
//! skipped so that the suite stays green while they are fixed. `WEFT_MALFORMED_KNOWN=1`
//! runs them too and prints which of them pass by now (remove those from the list).

mod common;

use std::collections::BTreeSet;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use common::{s, scratch, stderr, weft};

// ------------------------------------------------------------------------- the tables

/// A table of corpus files (the file's name under its directory, and what the error
/// must say besides naming it) and the commands that read them (`{in}`: the file).
struct Table {
    dir: &'static str,
    files: &'static [(&'static str, &'static str)],
    commands: &'static [&'static str],
}

/// The twelve mesh files at the top of the corpus, less `non_manifold.obj` (it reads).
const MESHES: &[(&str, &str)] = &[
    ("truncated.obj", ":3: vertex with 2 coordinates"),
    ("nan_coordinate.obj", ":2: coordinate `nan` is not finite"),
    (
        "index_out_of_range.obj",
        ":4: vertex index 4 is out of range",
    ),
    (
        "index_zero.obj",
        ":4: vertex index 0; OBJ indices start at 1",
    ),
    (
        "index_negative_overflow.obj",
        ":4: relative vertex index -4",
    ),
    ("binary_garbage.obj", ":1: binary data (a NUL byte)"),
    ("binary_garbage.ply", ":1: not a PLY file"),
    ("empty.obj", "the mesh is empty"),
    ("truncated_binary.ply", "byte 169: element vertex"),
    ("huge_vertex_count.ply", "declares 4000000000 of them"),
    ("bad_header.ply", ":4: unknown type `flaot`"),
];

const MESH_COMMANDS: &[&str] = &[
    "mesh info {in}",
    "mesh hierarchy {in} --json",
    "mesh hierarchy {in} --out {s}/levels",
    "render {in} --out {s}/picture.png",
    "render {f}/triangle.obj --body {in} --out {s}/picture.png",
    "export --frames {f}/frames.npy --faces {in} --format pc2 --out {s}/out.pc2",
    "export --frames {f}/frames.npy --faces {f}/triangle.obj --format glb --body {in} --out {s}/out.glb",
    "simulate --garment {in} --motion walk --frames 1 --out {s}/sim",
    "garment resize --garment {in} --to-betas 1 --out {s}/resized.obj",
    "garment drape --garment {in} --frames 1 --out {s}/draped.obj",
    "garment prepare --garment {in} --no-drape --out {s}/prepared.obj",
];

/// SMPL-format bodies (`body/`); `two_joints.npz` is a valid body with too few joints
/// for motions and is in [`SINGLE`].
const BODIES: &[(&str, &str)] = &[
    ("missing_shapedirs.npz", "no array `shapedirs`"),
    ("missing_faces.npz", "no array `f`"),
    ("missing_kintree_table.npz", "no array `kintree_table`"),
    ("v_template_int.npz", "`v_template` has dtype '<i4'"),
    ("faces_float.npz", "`f` has dtype '<f8'"),
    (
        "v_template_two_columns.npz",
        "`v_template` has shape (4, 2)",
    ),
    ("shapedirs_2d.npz", "`shapedirs` has shape (4, 6)"),
    ("weights_wrong_joints.npz", "`weights` has shape (4, 23)"),
    ("v_template_nan.npz", "v_template[1, 1] is NaN"),
    ("shapedirs_inf.npz", "shapedirs[0, 2, 1] is inf"),
    ("kintree_parent_out_of_range.npz", "joint 5 has parent 30"),
    ("kintree_child_before_parent.npz", "joint 4 has parent 7"),
    ("kintree_ids_out_of_order.npz", "row 1 holds 4 at column 3"),
    ("faces_index_out_of_range.npz", "face 3 uses vertex 4"),
    ("faces_index_negative.npz", "face 0 uses vertex -1"),
    ("no_faces.npz", "no faces"),
    ("weights_do_not_sum_to_one.npz", "row 0 sums to 0.7"),
    ("weights_negative.npz", "weights[0, 1] = -0.5"),
    ("j_regressor_rows_sum_to_half.npz", "row 0 sums to 0.5"),
    ("j_regressor_pickled.npz", "stored as a Python object"),
    ("posedirs_wrong_shape.npz", "`posedirs` has shape (4, 3, 5)"),
    ("zip_garbage.npz", "not a readable .npz (zip) archive"),
    ("text.npz", "not a readable .npz (zip) archive"),
    ("truncated.npz", "not a readable .npz (zip) archive"),
    ("empty.npz", "not a readable .npz (zip) archive"),
    ("empty_archive.npz", "no array `v_template`"),
    ("corrupt_member.npz", "checksum"),
    (
        "member_header_lies.npz",
        "shape (400, 3) of '<f8' needs 9600",
    ),
];

const BODY_COMMANDS: &[&str] = &[
    "body info --body {in}",
    "body export --body {in} --out {s}/body.obj",
    "motion generate --kind walk --frames 2 --body {in} --out {s}/walk.npz",
    "garment generate --kind skirt --vertices 300 --body {in} --out {s}/skirt.obj",
];

/// AMASS-style motions (`amass/`).
const AMASS: &[(&str, &str)] = &[
    ("no_poses.npz", "no array `poses`"),
    ("no_trans.npz", "no array `trans`"),
    ("no_framerate.npz", "no frame rate"),
    ("poses_1d.npz", "`poses`: has shape [216]"),
    ("poses_wrong_width.npz", "`poses`: has shape (3, 50)"),
    ("poses_3d.npz", "`poses`: has shape [3, 24, 3]"),
    ("poses_no_frames.npz", "`poses`: has no frames"),
    ("poses_nan.npz", "`poses`: frame 1, value 7 is NaN"),
    ("poses_int.npz", "`poses` has dtype '<i8'"),
    ("trans_short.npz", "`trans` has shape (2, 3)"),
    ("trans_inf.npz", "`trans`: frame 1, coordinate 1 is inf"),
    ("trans_2_columns.npz", "`trans` has shape (3, 2)"),
    ("framerate_zero.npz", "`mocap_framerate`: frame rate 0"),
    ("framerate_1e9.npz", "frame rate 1000000000"),
    ("framerate_negative.npz", "frame rate -30"),
    ("framerate_nan.npz", "frame rate NaN"),
    ("framerate_array.npz", "`mocap_framerate`: has shape [2]"),
    ("frame_rate_zero.npz", "`mocap_frame_rate`: frame rate 0"),
    ("betas_nan.npz", "`betas`: beta 1 is NaN"),
    ("betas_2d.npz", "`betas` has shape (3, 10)"),
    ("zip_garbage.npz", "not a readable .npz (zip) archive"),
    ("truncated.npz", "not a readable .npz (zip) archive"),
    ("empty.npz", "not a readable .npz (zip) archive"),
    ("corrupt_member.npz", "checksum"),
    ("poses_header_lies.npz", "shape (3, 72) of '<f8' needs 1728"),
];

/// Commands that read a motion file (AMASS or BVH).
const MOTION_COMMANDS: &[&str] = &[
    "motion info {in}",
    "body pose --motion {in} --out {s}/posed.obj",
    "simulate --garment {f}/garment.obj --motion {in} --frames 1 --out {s}/sim",
];

/// BVH motions (`bvh/`).
const BVHS: &[(&str, &str)] = &[
    ("empty.bvh", "expected 'HIERARCHY'"),
    ("binary_garbage.bvh", "not UTF-8 text"),
    ("truncated_hierarchy.bvh", ":34: JOINT without a joint name"),
    ("missing_motion.bvh", "expected ROOT or MOTION"),
    ("frame_count_mismatch.bvh", "declares 3 frames"),
    ("frame_count_negative.bvh", "found '-1'"),
    ("frame_count_absurd.bvh", "declares 4000000000000 frames"),
    ("short_frame_line.bvh", "frame 2 has 31 values"),
    ("long_frame_line.bvh", "frame 2 has more than 33 values"),
    ("non_numeric_channel.bvh", "found 'abc'"),
    ("nan_channel.bvh", "found 'nan'"),
    ("frame_time_zero.bvh", "frame time 0;"),
    ("frame_time_negative.bvh", "frame time -0.033"),
    (
        "frame_time_missing.bvh",
        "expected 'Frame' after the frame count",
    ),
    ("unknown_channel.bvh", "channel 6 is 'Wrotation'"),
    ("channel_count_mismatch.bvh", "declares 4 channels"),
    ("unbalanced_open_brace.bvh", "a '}' is missing"),
    (
        "unbalanced_close_brace.bvh",
        "'}' without an open joint block",
    ),
    ("no_root.bvh", "JOINT outside any ROOT block"),
    ("offset_not_numeric.bvh", "OFFSET of 'L_Hip', found 'x'"),
    (
        "unmappable_joints.bvh",
        "no BVH joint maps to SMPL joint 'left_hip'",
    ),
];

/// BVH joint-name maps (`map/`), given to a valid BVH.
const MAPS: &[(&str, &str)] = &[
    ("syntax_error.toml", "not valid TOML"),
    ("value_not_string.toml", "'Hips' maps to 3"),
    (
        "unknown_smpl_joint.toml",
        "'pelvix', which is no SMPL joint",
    ),
    ("empty.toml", "the map is empty"),
    ("conflicting.toml", "name the same joint"),
    ("binary_garbage.toml", "UTF-8"),
    ("syntax_error.json", "not valid JSON"),
    ("not_an_object.json", "expected one JSON object"),
    ("value_not_string.json", "'Hips' maps to"),
    ("empty_object.json", "the map is empty"),
    ("unknown_format.yaml", "unknown map format"),
    (
        "no_joint_in_file.toml",
        "no BVH joint maps to SMPL joint 'pelvis'",
    ),
];

const MAP_COMMANDS: &[&str] = &["motion info {f}/walk.bvh --map {in}"];

/// Frame arrays (`npy/`) for the 3-vertex template.
const NPYS: &[(&str, &str)] = &[
    ("int32.npy", "dtype '<i4'"),
    ("complex.npy", "dtype '<c8' is not supported"),
    ("big_endian.npy", "big-endian"),
    ("object.npy", "dtype '|O' is not supported"),
    ("two_d.npy", "shape (2, 9)"),
    ("one_d.npy", "shape (18,)"),
    ("four_d.npy", "shape (1, 2, 3, 3)"),
    ("last_axis_2.npy", "shape (3, 3, 2)"),
    ("zero_frames.npy", "shape (0, 3, 3)"),
    ("wrong_vertex_count.npy", "has 6 vertices per frame"),
    ("nan.npy", "is NaN"),
    ("inf.npy", "is -inf"),
    ("f64_beyond_f32.npy", "does not fit in a 32-bit float"),
    ("truncated.npy", "the data has 62 bytes"),
    ("header_lies.npy", "shape (5, 3, 3) of '<f4' needs 180"),
    ("header_huge.npy", "shape (1000000000000, 3, 3)"),
    ("header_cut.npy", "truncated"),
    ("fortran_order.npy", "fortran_order is True"),
    ("unknown_header_key.npy", "unknown key 'x'"),
    ("version_9.npy", "version 9.0"),
    ("not_npy.npy", "not a .npy file"),
    ("empty.npy", "not a .npy file"),
];

const NPY_COMMANDS: &[&str] = &[
    "export --frames {in} --faces {f}/triangle.obj --format pc2 --out {s}/out.pc2",
    "export --frames {f}/frames.npy --faces {f}/triangle.obj --format glb --body {f}/triangle.obj --body-frames {in} --out {s}/out.glb",
];

/// Directories of OBJ frames (`frames/`).
const FRAME_DIRS: &[(&str, &str)] = &[
    ("mixed_vertex_counts", "4 vertices, but"),
    ("bad_frame", "vertex with 2 coordinates"),
    ("no_obj_files", "no .obj"),
    ("nan_frame", "coordinate `nan` is not finite"),
];

/// (`weft render DIR` draws frames of different vertex counts side by side, so it reads
/// three of these; see [`SINGLE`].)
const FRAME_DIR_COMMANDS: &[&str] =
    &["export --frames {in} --faces {f}/triangle.obj --format obj --out {s}/sequence"];

/// Dataset configs (`config/data/`); those whose error names another file are in
/// [`SINGLE`].
const DATA_CONFIGS: &[(&str, &str)] = &[
    ("syntax_error.toml", "line 3, column 10"),
    ("unknown_top_key.toml", "unknown field `fpss`"),
    ("unknown_nested_key.toml", "unknown field `garmentz`"),
    ("unknown_garment_key.toml", "unknown field `colour`"),
    ("unknown_section.toml", "unknown field `trian`"),
    ("frames_string.toml", "invalid type: string \"many\""),
    ("seed_negative.toml", "integer `-1`, expected u64"),
    ("fps_string.toml", "invalid type: string \"30\""),
    ("betas_not_array.toml", "expected a sequence"),
    ("fps_zero.toml", "fps"),
    ("fps_huge.toml", "fps"),
    ("fps_nan.toml", "fps"),
    ("frames_zero.toml", "frames"),
    ("substeps_zero.toml", "substeps"),
    ("substeps_1000.toml", "substeps"),
    ("warmup_frames_huge.toml", "warmup_frames"),
    ("material_unknown.toml", "\"kevlar\""),
    ("beta_sigma_negative.toml", "beta_sigma"),
    ("beta_limit_zero.toml", "beta_limit"),
    ("beta_components_100.toml", "beta_components"),
    ("betas_nan.toml", "train.betas[0][0]"),
    ("garment_kind_unknown.toml", "train.garments[0].kind"),
    ("garment_vertices_10.toml", "train.garments[0].vertices"),
    (
        "garment_material_unknown.toml",
        "train.garments[0].material",
    ),
    ("motion_kind_unknown.toml", "train.motions[0].kind"),
    ("motion_kind_and_file.toml", "train.motions[0]"),
    ("motion_frames_zero.toml", "train.motions[0].frames"),
    ("no_garments.toml", "train.garments"),
    ("empty.toml", "train.garments"),
    ("binary_garbage.toml", "UTF-8"),
];

const DATA_CONFIG_COMMANDS: &[&str] = &["data generate --config {in} --out {s}/dataset"];

/// Model and training configs (`config/train/`).
const TRAIN_CONFIGS: &[(&str, &str)] = &[
    ("syntax_error.toml", "not valid TOML"),
    ("unknown_top_key.toml", "unknown key `stepz`"),
    ("unknown_section.toml", "unknown key `trian`"),
    ("unknown_model_key.toml", "`model.feature_widht`"),
    ("unknown_nested_key.toml", "`train.optimizer.momentum`"),
    ("steps_string.toml", "invalid type: string \"many\""),
    ("steps_negative.toml", "integer `-5`"),
    ("steps_zero.toml", "train.steps = 0"),
    ("window_zero.toml", "train.window = 0"),
    ("batch_zero.toml", "train.batch = 0"),
    ("learning_rate_negative.toml", "train.learning_rate = -0.1"),
    ("learning_rate_nan.toml", "train.learning_rate = NaN"),
    ("optimizer_unknown.toml", "unknown variant `adamx`"),
    ("pool_ratio_2.toml", "pool_ratio"),
    ("pooling_unknown.toml", "unknown variant `random`"),
    ("joints_wrong_type.toml", "invalid type: string \"24\""),
    ("model_not_table.toml", "`model` must be a table"),
    ("preset_unknown.toml", "\"gpu\""),
    ("binary_garbage.toml", "UTF-8"),
];

const TRAIN_CONFIG_COMMANDS: &[&str] =
    &["train --data {s}/no_dataset --out {s}/run --config {in} --quiet"];

/// Dataset directories (`dataset/`).
const DATASETS: &[(&str, &str)] = &[
    ("manifest_not_json", "not a weft dataset manifest"),
    ("manifest_empty", "not a weft dataset manifest"),
    ("manifest_array", "not a weft dataset manifest"),
    ("manifest_truncated", "not a weft dataset manifest"),
    ("manifest_wrong_format", "not a weft dataset manifest"),
    ("no_manifest", "cannot read the manifest"),
];

const DATASET_COMMANDS: &[&str] = &[
    "data info {in}",
    "data info {in} --verify --json",
    "train --data {in} --out {s}/run --steps 1 --quiet",
];

/// Run directories (`run/`).
const RUNS: &[(&str, &str)] = &[
    ("no_config", "config.toml"),
    ("config_syntax_error", "not valid TOML"),
    ("config_no_version", "no integer format_version"),
    ("config_version_99", "format_version 99"),
    ("config_unknown_model", "unknown model `transformer`"),
    ("config_no_preset", "no preset"),
    // `attribute` reads Multilevel runs only and says so; `animate` names the key
    // (hood_cli.rs checks that): both name the file.
    (
        "config_hood_unknown_key",
        "config_hood_unknown_key/config.toml",
    ),
    ("config_unknown_model_key", "`model.feature_widht`"),
    ("config_no_model_table", "no [model] table"),
    ("config_binary", "UTF-8"),
    ("no_checkpoint", "no checkpoint yet"),
    ("latest_garbage", "expected a name like step-000100.bpk"),
    ("latest_dangling", "step-000100.bpk"),
    ("checkpoint_garbage", "step-000100.bpk"),
    ("checkpoint_empty", "step-000100.bpk"),
];

const RUN_COMMANDS: &[&str] = &[
    "animate {in} --garment {f}/garment.obj --motion walk --frames 2 --format obj --out {s}/animation",
    "attribute {in} --vertex 0 --garment {f}/garment.obj --out {s}/attribution.png",
];

const TABLES: &[Table] = &[
    Table {
        dir: "",
        files: MESHES,
        commands: MESH_COMMANDS,
    },
    Table {
        dir: "body",
        files: BODIES,
        commands: BODY_COMMANDS,
    },
    Table {
        dir: "amass",
        files: AMASS,
        commands: MOTION_COMMANDS,
    },
    Table {
        dir: "bvh",
        files: BVHS,
        commands: MOTION_COMMANDS,
    },
    Table {
        dir: "map",
        files: MAPS,
        commands: MAP_COMMANDS,
    },
    Table {
        dir: "npy",
        files: NPYS,
        commands: NPY_COMMANDS,
    },
    Table {
        dir: "frames",
        files: FRAME_DIRS,
        commands: FRAME_DIR_COMMANDS,
    },
    Table {
        dir: "config/data",
        files: DATA_CONFIGS,
        commands: DATA_CONFIG_COMMANDS,
    },
    Table {
        dir: "config/train",
        files: TRAIN_CONFIGS,
        commands: TRAIN_CONFIG_COMMANDS,
    },
    Table {
        dir: "dataset",
        files: DATASETS,
        commands: DATASET_COMMANDS,
    },
    Table {
        dir: "run",
        files: RUNS,
        commands: RUN_COMMANDS,
    },
];

/// Single cases: (command line, the file name or `--flag` the error must name, what
/// else it must say). Bad arguments first, then corpus files read by one command only.
const SINGLE: &[(&str, &str, &str)] = &[
    // Negative numbers given to unsigned options name the option.
    ("mesh hierarchy --levels -1", "--levels", "-1"),
    ("motion generate --kind walk --frames -5 --out {s}/walk.npz", "--frames", "-5"),
    ("motion generate --kind walk --seed -1 --out {s}/walk.npz", "--seed", "-1"),
    ("body pose --motion {f}/walk.npz --frame -1 --out {s}/posed.obj", "--frame", "-1"),
    ("body import-mpfb {s}/a_dir --samples -3 --out {s}/body.npz", "--samples", "-3"),
    ("render {f}/triangle.obj --size -5 --out {s}/picture.png", "--size", "-5"),
    ("render {f}/triangle.obj --views -1 --out {s}/picture.png", "--views", "-1"),
    ("render {f}/triangle.obj --fps -1 --out {s}/picture.png", "--fps", "-1"),
    ("garment generate --kind skirt --vertices -100 --out {s}/skirt.obj", "--vertices", "-100"),
    ("garment generate --kind skirt --seed -1 --out {s}/skirt.obj", "--seed", "-1"),
    ("garment drape --garment {f}/garment.obj --frames -1 --out {s}/draped.obj", "--frames", "-1"),
    ("garment drape --garment {f}/garment.obj --settle-speed -1 --out {s}/draped.obj", "--settle-speed", "-1"),
    ("garment prepare --garment {f}/garment.obj --frames -3 --out {s}/prepared.obj", "--frames", "-3"),
    ("export --frames {f}/frames.npy --faces {f}/triangle.obj --format mdd --fps -30 --out {s}/out.mdd", "--fps", "-30"),
    ("simulate --garment {f}/garment.obj --motion walk --frames -5 --out {s}/sim", "--frames", "-5"),
    ("simulate --garment {f}/garment.obj --motion walk --substeps -1 --out {s}/sim", "--substeps", "-1"),
    ("simulate --garment {f}/garment.obj --motion walk --warmup -1 --out {s}/sim", "--warmup", "-1"),
    ("simulate --garment {f}/garment.obj --motion walk --seed -1 --out {s}/sim", "--seed", "-1"),
    ("data generate --seed -1 --out {s}/dataset", "--seed", "-1"),
    ("train --data {s}/no_dataset --out {s}/run --steps -1", "--steps", "-1"),
    ("train --data {s}/no_dataset --out {s}/run --seed -1", "--seed", "-1"),
    ("eval {s}/no_run --data {s}/no_dataset --max-sequences -1", "--max-sequences", "-1"),
    ("attribute {s}/no_run --vertex -1 --garment {f}/garment.obj --out {s}/a.png", "--vertex", "-1"),
    ("attribute {s}/no_run --vertex 0 --frame -2 --garment {f}/garment.obj --out {s}/a.png", "--frame", "-2"),
    ("attribute {s}/no_run --vertex 0 --samples -1 --garment {f}/garment.obj --out {s}/a.png", "--samples", "-1"),
    ("animate {s}/no_run --garment {f}/garment.obj --motion walk --frames -5 --format obj --out {s}/animation", "--frames", "-5"),
    ("animate {s}/no_run --garment {f}/garment.obj --motion walk --seed -1 --format obj --out {s}/animation", "--seed", "-1"),
    ("demo --steps -1 --out {s}/demo", "--steps", "-1"),
    // Zero where at least one is needed.
    ("mesh hierarchy --levels 0", "--levels", "0"),
    ("motion generate --kind walk --frames 0 --out {s}/walk.npz", "--frames", "0"),
    ("motion generate --kind walk --fps 0 --out {s}/walk.npz", "--fps", "0"),
    ("render {f}/triangle.obj --fps 0 --animate --out {s}/picture.png", "--fps", "0"),
    ("render {f}/triangle.obj --views 0 --camera turntable --out {s}/picture.png", "--views", "0"),
    ("export --frames {f}/frames.npy --faces {f}/triangle.obj --format pc2 --fps 0 --out {s}/out.pc2", "--fps", "0"),
    ("garment drape --garment {f}/garment.obj --frames 0 --out {s}/draped.obj", "--frames", "0"),
    ("simulate --garment {f}/garment.obj --motion walk --frames 0 --out {s}/sim", "--frames", "0"),
    ("simulate --garment {f}/garment.obj --motion walk --substeps 0 --out {s}/sim", "--substeps", "0"),
    ("simulate --garment {f}/garment.obj --motion walk --fps 0 --out {s}/sim", "--fps", "0"),
    ("train --data {s}/no_dataset --out {s}/run --steps 0", "--steps", "0"),
    ("eval {m}/run/no_checkpoint --data {m}/dataset/manifest_empty --max-sequences 0", "--max-sequences", "0"),
    ("attribute {m}/run/no_checkpoint --vertex 0 --samples 0 --garment {f}/garment.obj --out {s}/a.png", "--samples", "0"),
    ("attribute {m}/run/no_checkpoint --vertex 0 --size 0 --garment {f}/garment.obj --out {s}/a.png", "--size", "0"),
    ("animate {m}/run/no_checkpoint --garment {f}/garment.obj --motion walk --frames 0 --format obj --out {s}/animation", "--frames", "0"),
    ("animate {m}/run/no_checkpoint --garment {f}/garment.obj --motion walk --fps 0 --format obj --out {s}/animation", "--fps", "0"),
    ("demo --steps 0 --out {s}/demo", "--steps", "0"),
    // Non-finite numbers.
    ("motion generate --kind walk --fps nan --out {s}/walk.npz", "--fps", "NaN"),
    ("motion generate --kind walk --speed nan --out {s}/walk.npz", "--speed", "NaN"),
    ("motion generate --kind walk --amplitude inf --out {s}/walk.npz", "--amplitude", "inf"),
    ("motion generate --kind walk --betas nan --out {s}/walk.npz", "--betas", "NaN"),
    ("motion info {f}/walk.bvh --scale nan", "--scale", "NaN"),
    ("motion info {m}/amass/no_framerate.npz --fps nan", "--fps", "NaN"),
    ("body export --betas nan --out {s}/body.obj", "--betas", "NaN"),
    ("body export --betas inf --out {s}/body.obj", "--betas", "inf"),
    ("body export --betas 0,-inf --out {s}/body.obj", "--betas", "inf"),
    ("render {f}/triangle.obj --range nan:1 --out {s}/picture.png", "--range", "nan:1"),
    ("render {f}/triangle.obj --default-body --betas nan --out {s}/picture.png", "--betas", "NaN"),
    ("garment generate --kind skirt --flare nan --out {s}/skirt.obj", "--flare", "NaN"),
    ("garment generate --kind skirt --betas nan --out {s}/skirt.obj", "--betas", "NaN"),
    ("garment resize --garment {f}/garment.obj --to-betas nan --out {s}/resized.obj", "--to-betas", "NaN"),
    ("garment resize --garment {f}/garment.obj --from-betas inf --to-betas 1 --out {s}/resized.obj", "--from-betas", "inf"),
    ("garment drape --garment {f}/garment.obj --betas nan --out {s}/draped.obj", "--betas", "NaN"),
    ("garment drape --garment {f}/garment.obj --settle-speed nan --out {s}/draped.obj", "--settle-speed", "NaN"),
    ("export --frames {f}/frames.npy --faces {f}/triangle.obj --format mdd --fps nan --out {s}/out.mdd", "--fps", "NaN"),
    ("simulate --garment {f}/garment.obj --motion walk --fps nan --out {s}/sim", "--fps", "NaN"),
    ("simulate --garment {f}/garment.obj --motion walk --betas nan --out {s}/sim", "--betas", "NaN"),
    ("animate {s}/no_run --garment {f}/garment.obj --motion walk --push-out nan --format pc2 --out {s}/a.pc2", "--push-out", "NaN"),
    ("animate {s}/no_run --garment {f}/garment.obj --motion walk --fps nan --format pc2 --out {s}/a.pc2", "--fps", "NaN"),
    ("animate {s}/no_run --garment {f}/garment.obj --motion walk --betas nan --format pc2 --out {s}/a.pc2", "--betas", "NaN"),
    ("attribute {s}/no_run --vertex 0 --garment {f}/garment.obj --betas nan --out {s}/a.png", "--betas", "NaN"),
    // Out of range.
    ("motion generate --kind walk --betas 100 --out {s}/walk.npz", "--betas", "--allow-extreme-shapes"),
    ("motion generate --kind walk --betas -100 --out {s}/walk.npz", "--betas", "--allow-extreme-shapes"),
    ("motion generate --kind walk --betas 1,2,3,4,5,6,7,8,9,10,11 --out {s}/walk.npz", "--betas", "11 shape coefficients"),
    ("motion generate --kind walk --fps 1e9 --out {s}/walk.npz", "--fps", "at most 1000"),
    ("motion generate --kind walk --amplitude 100 --out {s}/walk.npz", "--amplitude", "100"),
    ("motion generate --kind walk --amplitude -1 --out {s}/walk.npz", "--amplitude", "-1"),
    ("motion info {f}/walk.bvh --scale 0", "--scale", "0"),
    ("motion info {f}/walk.bvh --scale -1", "--scale", "-1"),
    ("motion info {m}/amass/no_framerate.npz --fps 0", "--fps", "0"),
    ("body export --betas 100 --out {s}/body.obj", "--betas", "--allow-extreme-shapes"),
    ("body export --betas 0,-6 --out {s}/body.obj", "--betas", "--allow-extreme-shapes"),
    ("body pose --motion {f}/walk.npz --frame 99 --out {s}/posed.obj", "walk.npz", "frame 99"),
    ("body import-mpfb {s}/a_dir --betas 0 --out {s}/body.npz", "--betas", "0"),
    ("body import-mpfb {s}/a_dir --betas 1000 --out {s}/body.npz", "--betas", "1000"),
    ("mesh hierarchy --levels 100", "--levels", "100"),
    ("render {f}/triangle.obj --size 10 --out {s}/picture.png", "--size", "10"),
    ("render {f}/triangle.obj --range 5:1 --out {s}/picture.png", "--range", "5:1"),
    ("render {f}/triangle.obj --default-body --betas 100 --out {s}/picture.png", "--betas", "--allow-extreme-shapes"),
    ("garment generate --kind skirt --vertices 0 --out {s}/skirt.obj", "--vertices", "0"),
    ("garment generate --kind skirt --vertices 10 --out {s}/skirt.obj", "--vertices", "10"),
    ("garment generate --kind skirt --vertices 1000000000 --out {s}/skirt.obj", "--vertices", "1000000000"),
    ("garment generate --kind skirt --vertices 1e3 --out {s}/skirt.obj", "--vertices", "1e3"),
    ("garment generate --kind skirt --flare 2 --out {s}/skirt.obj", "--flare", "2"),
    ("garment generate --kind skirt --betas 100 --out {s}/skirt.obj", "--betas", "--allow-extreme-shapes"),
    ("garment resize --garment {f}/garment.obj --to-betas 100 --out {s}/resized.obj", "--to-betas", "--allow-extreme-shapes"),
    ("garment resize --garment {f}/garment.obj --from-betas 100 --to-betas 1 --out {s}/resized.obj", "--from-betas", "--allow-extreme-shapes"),
    ("garment prepare --garment {f}/garment.obj --betas 100 --no-drape --out {s}/prepared.obj", "--betas", "--allow-extreme-shapes"),
    ("garment drape --garment {f}/garment.obj --settle-speed 0 --out {s}/draped.obj", "--settle-speed", "0"),
    ("simulate --garment {f}/garment.obj --motion walk --warmup 1000000000 --out {s}/sim", "--warmup", "1000000000"),
    ("simulate --garment {f}/garment.obj --motion walk --substeps 1000000 --out {s}/sim", "--substeps", "1000000"),
    ("simulate --garment {f}/garment.obj --motion walk --frames 1000000000 --out {s}/sim", "--frames", "1000000000"),
    ("simulate --garment {f}/garment.obj --motion walk --betas 100 --out {s}/sim", "--betas", "--allow-extreme-shapes"),
    ("data generate --shard 3/2 --out {s}/dataset", "--shard", "3/2"),
    ("data generate --shard 0/0 --out {s}/dataset", "--shard", "0/0"),
    ("data generate --shard abc --out {s}/dataset", "--shard", "abc"),
    ("attribute {s}/no_run --vertex 0 --size 100000 --garment {f}/garment.obj --out {s}/a.png", "--size", "100000"),
    ("animate {s}/no_run --garment {f}/garment.obj --motion walk --push-out -1 --format pc2 --out {s}/a.pc2", "--push-out", "-1"),
    ("animate {s}/no_run --garment {f}/garment.obj --motion walk --frames 1000000000 --format pc2 --out {s}/a.pc2", "--frames", "1000000000"),
    // Not numbers at all.
    ("motion generate --kind walk --frames many --out {s}/walk.npz", "--frames", "many"),
    ("motion generate --kind walk --betas abc --out {s}/walk.npz", "--betas", "abc"),
    ("garment generate --kind skirt --vertices abc --out {s}/skirt.obj", "--vertices", "abc"),
    ("simulate --garment {f}/garment.obj --motion walk --substeps 2.5 --out {s}/sim", "--substeps", "2.5"),
    ("train --data {s}/no_dataset --out {s}/run --steps ten", "--steps", "ten"),
    // Unknown enum values and names.
    ("motion generate --kind moonwalk --out {s}/walk.npz", "--kind", "moonwalk"),
    ("motion generate --kind walk --npz-up x --out {s}/walk.npz", "--npz-up", "x"),
    ("motion info {f}/walk.npz --up w", "--up", "w"),
    ("motion info {f}/walk.bvh --map nosuchpreset", "nosuchpreset", "smpl"),
    ("body pose --motion {f}/walk.npz --skinning xyz --out {s}/posed.obj", "--skinning", "xyz"),
    ("body import-mpfb {s}/a_dir --rest-pose x --out {s}/body.npz", "--rest-pose", "x"),
    ("render {f}/triangle.obj --camera top --out {s}/picture.png", "--camera", "top"),
    ("render {f}/triangle.obj --colormap rainbow --out {s}/picture.png", "--colormap", "rainbow"),
    ("render {f}/triangle.obj --shading toon --out {s}/picture.png", "--shading", "toon"),
    ("garment generate --kind cape --out {s}/skirt.obj", "--kind", "cape"),
    ("garment generate --kind skirt --length ankle --out {s}/skirt.obj", "--length", "ankle"),
    ("garment generate --kind dress --dress-top tube --out {s}/dress.obj", "--dress-top", "tube"),
    ("garment drape --garment {f}/garment.obj --material kevlar --out {s}/draped.obj", "--material", "kevlar"),
    ("garment prepare --garment {f}/garment.obj --material kevlar --out {s}/prepared.obj", "--material", "kevlar"),
    ("export --frames {f}/frames.npy --faces {f}/triangle.obj --format fbx --out {s}/out.fbx", "--format", "fbx"),
    ("export --frames {f}/frames.npy --faces {f}/triangle.obj --format pc2 --body {f}/triangle.obj --out {s}/out.pc2", "--body", "glb"),
    ("simulate --garment {f}/garment.obj --motion moonwalk --out {s}/sim", "--motion", "moonwalk"),
    ("simulate --garment {f}/garment.obj --motion walk --material kevlar --out {s}/sim", "--material", "kevlar"),
    ("simulate --garment {f}/garment.obj --motion walk --attach all --out {s}/sim", "--attach", "all"),
    ("data generate --preset huge --out {s}/dataset", "--preset", "huge"),
    ("train --data {s}/no_dataset --out {s}/run --model transformer", "--model", "transformer"),
    ("train --data {s}/no_dataset --out {s}/run --model hood", "--data", "not a dataset"),
    ("train --out {s}/run --model multilevel", "--data", "trains on a dataset"),
    ("train --data {s}/no_dataset --out {s}/run --preset gpu", "--preset", "gpu"),
    ("config show --preset gpu", "--preset", "gpu"),
    ("config show --model transformer", "--model", "transformer"),
    ("eval {s}/no_run --data {s}/no_dataset --split dev", "--split", "dev"),
    ("animate {s}/no_run --garment {f}/garment.obj --motion walk --format fbx --out {s}/a.fbx", "--format", "fbx"),
    ("animate {s}/no_run --garment {f}/garment.obj --motion moonwalk --format pc2 --out {s}/a.pc2", "--motion", "moonwalk"),
    ("attribute {s}/no_run --vertex 0 --garment {f}/garment.obj --motion moonwalk --out {s}/a.png", "--motion", "moonwalk"),
    ("frobnicate", "frobnicate", "unrecognized subcommand"),
    ("mesh frobnicate", "frobnicate", "unrecognized subcommand"),
    ("mesh info --colour", "--colour", "unexpected argument"),
    // Missing arguments and files.
    ("mesh info", "<FILE>", "required"),
    ("motion generate --out {s}/walk.npz", "--kind", "required"),
    ("export --faces {f}/triangle.obj --format pc2 --out {s}/out.pc2", "--frames", "required"),
    ("mesh info {s}/missing.obj", "missing.obj", "No such file"),
    ("motion info {s}/missing.npz", "missing.npz", "No such file"),
    ("motion info {s}/missing.bvh", "missing.bvh", "No such file"),
    ("motion info {f}/walk.bvh --map {s}/missing.toml", "missing.toml", "No such file"),
    ("body info --body {s}/missing.npz", "missing.npz", "No such file"),
    ("render {s}/missing.obj --out {s}/picture.png", "missing.obj", "No such file"),
    ("render {f}/triangle.obj --color-by {s}/missing.npy --out {s}/picture.png", "missing.npy", "No such file"),
    ("garment resize --garment {s}/missing.obj --to-betas 1 --out {s}/resized.obj", "missing.obj", "No such file"),
    ("export --frames {s}/missing.npy --faces {f}/triangle.obj --format pc2 --out {s}/out.pc2", "missing.npy", "No such file"),
    ("export --frames {f}/frames.npy --faces {s}/missing.obj --format pc2 --out {s}/out.pc2", "missing.obj", "No such file"),
    ("simulate --garment {s}/missing.obj --motion walk --out {s}/sim", "missing.obj", "No such file"),
    ("simulate --garment {f}/garment.obj --motion {s}/missing.npz --out {s}/sim", "missing.npz", "No such file"),
    ("simulate --garment {f}/garment.obj --body {s}/missing.npz --motion walk --out {s}/sim", "missing.npz", "No such file"),
    ("data generate --config {s}/missing.toml --out {s}/dataset", "missing.toml", "No such file"),
    ("data info {s}/missing", "missing", "No such file"),
    ("data merge {s}/missing", "missing", "manifest"),
    ("train --data {s}/no_dataset --out {s}/run --config {s}/missing.toml", "missing.toml", "No such file"),
    ("train --data {s}/no_dataset --out {s}/run --steps 1", "no_dataset", "no such dataset directory"),
    ("eval {m}/run/no_checkpoint", "--data", "required"),
    ("eval {s}/no_run --data {m}/dataset/manifest_empty", "no_run", "config.toml"),
    ("eval {m}/run/config_syntax_error --data {m}/dataset/manifest_empty", "config_syntax_error", "not valid TOML"),
    ("eval {m}/run/no_checkpoint --data {m}/dataset/manifest_not_json", "no_checkpoint", "no checkpoint yet"),
    ("attribute {s}/no_run --vertex 0 --garment {f}/garment.obj --out {s}/a.png", "no_run", "config.toml"),
    ("animate {s}/no_run --garment {f}/garment.obj --motion walk --format pc2 --out {s}/a.pc2", "no_run", "config.toml"),
    ("body import-mpfb {s}/no_mpfb --out {s}/body.npz", "no_mpfb", "no MPFB2 data"),
    // Directories where files are expected.
    ("mesh info {s}/a_dir", "a_dir", ""),
    ("motion info {s}/a_dir", "a_dir", ""),
    ("motion info {f}/walk.bvh --map {s}/a_dir", "a_dir", ""),
    ("body info --body {s}/a_dir", "a_dir", ""),
    ("body export --out {s}/a_dir", "a_dir", ""),
    ("body pose --motion {f}/walk.npz --out {s}/a_dir", "a_dir", ""),
    ("render {f}/triangle.obj --color-by {s}/a_dir --out {s}/picture.png", "a_dir", ""),
    ("render {f}/triangle.obj --out {s}/a_dir", "a_dir", ""),
    ("garment generate --kind skirt --vertices 300 --out {s}/a_dir", "a_dir", ""),
    ("garment resize --garment {s}/a_dir --to-betas 1 --out {s}/resized.obj", "a_dir", ""),
    ("garment resize --garment {f}/garment.obj --to-betas 1 --out {s}/a_dir", "a_dir", ""),
    ("export --frames {f}/frames.npy --faces {s}/a_dir --format pc2 --out {s}/out.pc2", "a_dir", ""),
    ("export --frames {f}/frames.npy --faces {f}/triangle.obj --format pc2 --out {s}/a_dir", "a_dir", ""),
    ("motion generate --kind walk --frames 2 --out {s}/a_dir", "a_dir", ""),
    ("data generate --config {s}/a_dir --out {s}/dataset", "a_dir", ""),
    ("train --data {s}/no_dataset --out {s}/run --config {s}/a_dir", "a_dir", ""),
    // Files where directories are expected.
    ("mesh hierarchy --out {s}/a_file.obj", "a_file.obj", ""),
    ("export --frames {f}/frames.npy --faces {f}/triangle.obj --format obj --out {s}/a_file.obj", "a_file.obj", ""),
    ("body pose --motion {f}/walk.npz --all-frames --out {s}/a_file.obj", "a_file.obj", ""),
    ("simulate --garment {f}/garment.obj --motion walk --frames 1 --out {s}/a_file.obj", "a_file.obj", ""),
    ("data generate --out {s}/a_file.obj", "a_file.obj", ""),
    ("data info {s}/a_file.obj", "a_file.obj", ""),
    ("data merge {s}/a_file.obj", "a_file.obj", ""),
    ("train --data {s}/a_file.obj --out {s}/run --steps 1", "a_file.obj", ""),
    ("eval {s}/a_file.obj --data {m}/dataset/manifest_empty", "a_file.obj", ""),
    ("animate {s}/a_file.obj --garment {f}/garment.obj --motion walk --format pc2 --out {s}/a.pc2", "a_file.obj", ""),
    ("body import-mpfb {s}/a_file.obj --out {s}/body.npz", "a_file.obj", ""),
    ("demo --out {s}/a_file.obj", "a_file.obj", ""),
    // Outputs of an unknown kind (a missing parent directory is created, not refused).
    ("body export --out {s}/body.stl", "body.stl", "unknown mesh format"),
    ("body pose --motion {f}/walk.npz --out {s}/posed.stl", "posed.stl", "unknown mesh format"),
    ("motion generate --kind walk --frames 2 --out {s}/walk.fbx", "walk.fbx", "unknown motion format"),
    ("render {f}/triangle.obj --out {s}/picture.jpg", "picture.jpg", ".png"),
    ("garment generate --kind skirt --vertices 300 --out {s}/skirt.stl", "skirt.stl", ""),
    ("garment resize --garment {f}/garment.obj --to-betas 1 --out {s}/resized.stl", "resized.stl", "unknown mesh format"),
    ("garment prepare --garment {f}/garment.obj --no-drape --weights {s}/weights.txt --out {s}/prepared.obj", "weights.txt", ".npy"),
    // Inputs of the wrong kind.
    ("mesh info {f}/frames.npy", "frames.npy", "unknown mesh format"),
    ("motion info {f}/triangle.obj", "triangle.obj", "unknown motion format"),
    ("export --frames {f}/triangle.obj --faces {f}/triangle.obj --format pc2 --out {s}/out.pc2", "triangle.obj", ".npy"),
    ("render {f}/triangle.obj --color-by {f}/frames.npy --out {s}/picture.png", "frames.npy", "one value per vertex"),
    ("render {f}/triangle.obj --color-by {m}/npy/two_d.npy --out {s}/picture.png", "two_d.npy", "one value per vertex"),
    ("render {f}/triangle.obj --color-by {m}/npy/not_npy.npy --out {s}/picture.png", "not_npy.npy", "not a .npy file"),
    ("render {f}/triangle.obj --color-by {m}/npy/truncated.npy --out {s}/picture.png", "truncated.npy", "62 bytes"),
    ("render {f}/triangle.obj --body {m}/body/v_template_nan.npz --out {s}/picture.png", "v_template_nan.npz", "is NaN"),
    ("render {m}/frames/bad_frame --out {s}/sheet.png", "bad_frame", "vertex with 2 coordinates"),
    ("render {m}/frames/nan_frame --out {s}/sheet.png", "nan_frame", "coordinate `nan` is not finite"),
    ("render {m}/frames/no_obj_files --out {s}/sheet.png", "no_obj_files", "no .obj"),
    ("body pose --motion walk --out {s}/posed.obj", "walk", "unknown motion format"),
    // Bodies that read but cannot drive a motion.
    ("body pose --body {m}/body/two_joints.npz --motion {f}/walk.npz --out {s}/posed.obj", "two_joints.npz", "2 joints"),
    ("motion generate --kind walk --frames 2 --body {m}/body/two_joints.npz --out {s}/walk.npz", "two_joints.npz", "2 joints"),
    ("simulate --garment {f}/garment.obj --body {m}/body/two_joints.npz --motion walk --frames 1 --out {s}/sim", "two_joints.npz", "2 joints"),
    ("simulate --garment {f}/garment.obj --body {m}/body/kintree_parent_out_of_range.npz --motion walk --out {s}/sim", "kintree_parent_out_of_range.npz", "joint 5 has parent 30"),
    // Dataset configs whose error is about a file they name.
    ("data generate --config {m}/config/data/body_missing.toml --out {s}/dataset", "no_such_body.npz", "No such file"),
    ("data generate --config {m}/config/data/body_malformed.toml --out {s}/dataset", "kintree_parent_out_of_range.npz", "joint 5 has parent 30"),
    ("data generate --config {m}/config/data/motion_file_missing.toml --out {s}/dataset", "no_such_motion.npz", "No such file"),
    ("data generate --config {m}/config/data/motion_file_malformed.toml --out {s}/dataset", "poses_nan.npz", "is NaN"),
    ("data merge {m}/dataset/bad_part", "manifest.part-0-of-2.json", ""),
];

/// Cases that fail today, by their command line exactly as in the tables (a table row's
/// `{in}` replaced by `{m}/DIR/FILE`), with what goes wrong. Each is skipped until fixed.
const KNOWN: &[(&str, &str)] = &[];

// ------------------------------------------------------------------------- the runner

/// One command line to run and what its error must say.
struct Case {
    /// Words separated by single spaces, with placeholders.
    args: String,
    /// The file name or `--flag` the error must name.
    names: String,
    /// What else the error must say ("" when naming it is enough).
    says: String,
}

fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    for table in TABLES {
        for (file, says) in table.files {
            let path = if table.dir.is_empty() {
                format!("{{m}}/{file}")
            } else {
                format!("{{m}}/{}/{file}", table.dir)
            };
            for command in table.commands {
                out.push(Case {
                    args: command.replace("{in}", &path),
                    names: (*file).to_string(),
                    says: (*says).to_string(),
                });
            }
        }
    }
    for (args, names, says) in SINGLE {
        out.push(Case {
            args: (*args).to_string(),
            names: (*names).to_string(),
            says: (*says).to_string(),
        });
    }
    out
}

/// The corpus directory at the repository root.
fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/malformed")
}

/// Every path under `dir` (relative, sorted) with the size of each file: what a case
/// must leave as it found it.
fn listing(dir: &Path) -> Vec<String> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            let rel = path.strip_prefix(root).unwrap().display().to_string();
            match entry.metadata() {
                Ok(m) if m.is_dir() => {
                    out.push(format!("{rel}/"));
                    walk(root, &path, out);
                }
                Ok(m) => out.push(format!("{rel} ({} bytes)", m.len())),
                Err(_) => out.push(rel),
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

/// The valid inputs cases combine with the bad one.
fn fixtures(dir: &Path) {
    std::fs::write(dir.join("triangle.obj"), TRIANGLE).unwrap();
    let frame = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let frames: Vec<f32> = frame.iter().chain(&frame).copied().collect();
    weft_mesh::export::npy::write_npy(&dir.join("frames.npy"), &[2, 3, 3], &frames).unwrap();
    for (name, args) in [
        (
            "garment.obj",
            "garment generate --kind skirt --vertices 300",
        ),
        ("walk.npz", "motion generate --kind walk --frames 3"),
        ("walk.bvh", "motion generate --kind walk --frames 2"),
    ] {
        let out = dir.join(name);
        let mut all: Vec<&str> = args.split(' ').collect();
        all.extend(["--out", s(&out)]);
        let o = weft(&all);
        assert!(o.status.success(), "{all:?}: {}", stderr(&o));
    }
}

/// How long one case may run: every case fails before any real work, in well under a
/// second; a case that runs this long is stuck in work it should have refused.
const TIMEOUT: Duration = Duration::from_secs(20);

/// What one run did.
struct Run {
    code: Option<i32>,
    timed_out: bool,
    stdout: String,
    stderr: String,
    before: Vec<String>,
    after: Vec<String>,
    a_file_intact: bool,
}

fn run(case: &Case, index: usize, root: &Path, fixtures: &Path) -> Run {
    let dir = root.join(format!("case-{index:03}"));
    std::fs::create_dir_all(dir.join("a_dir")).unwrap();
    std::fs::write(dir.join("a_file.obj"), TRIANGLE).unwrap();
    let args: Vec<String> = case
        .args
        .split(' ')
        .map(|w| {
            w.replace("{m}", s(&corpus()))
                .replace("{f}", s(fixtures))
                .replace("{s}", s(&dir))
        })
        .collect();
    let logs = root.join("logs");
    let (out_path, err_path) = (
        logs.join(format!("{index:03}.out")),
        logs.join(format!("{index:03}.err")),
    );
    let before = listing(&dir);
    let mut child = Command::new(env!("CARGO_BIN_EXE_weft"))
        .args(&args)
        .current_dir(&dir)
        .env_remove("RUST_BACKTRACE")
        .env_remove("RUST_LIB_BACKTRACE")
        .stdin(Stdio::null())
        .stdout(File::create(&out_path).unwrap())
        .stderr(File::create(&err_path).unwrap())
        .spawn()
        .expect("the weft binary runs");
    let started = Instant::now();
    let (status, timed_out) = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break (Some(status), false);
        }
        if started.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            break (None, true);
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let read = |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap()).into_owned();
    Run {
        code: status.and_then(|s| s.code()),
        timed_out,
        stdout: read(&out_path),
        stderr: read(&err_path),
        before,
        after: listing(&dir),
        a_file_intact: std::fs::read_to_string(dir.join("a_file.obj"))
            .ok()
            .as_deref()
            == Some(TRIANGLE),
    }
}

/// What is wrong with `run` for `case`; empty when it failed as it must.
fn problems(case: &Case, run: &Run) -> Vec<String> {
    let mut p = Vec::new();
    if run.timed_out {
        p.push(format!(
            "still running after {} s (killed)",
            TIMEOUT.as_secs()
        ));
        return p;
    }
    match run.code {
        Some(0) => p.push("exit status 0".into()),
        None => p.push("killed by a signal".into()),
        Some(_) => {}
    }
    let err = &run.stderr;
    if err.contains("panicked") || err.contains("RUST_BACKTRACE") {
        p.push("panicked".into());
    }
    if !(err.ends_with('\n') && err.lines().count() == 1) {
        p.push(format!("{} lines on stderr, not one", err.lines().count()));
    }
    if !err.starts_with("error: ") {
        p.push("stderr does not start with `error: `".into());
    }
    if !err.contains(&case.names) {
        p.push(format!("the error does not name `{}`", case.names));
    }
    // Case-insensitive: a value is echoed as typed (`nan`) or as Rust prints it (`NaN`).
    if !err.to_lowercase().contains(&case.says.to_lowercase()) {
        p.push(format!("the error does not say `{}`", case.says));
    }
    if !run.stdout.is_empty() {
        p.push("printed to stdout".into());
    }
    if run.after != run.before || !run.a_file_intact {
        let new: Vec<&String> = run
            .after
            .iter()
            .filter(|x| !run.before.contains(x))
            .collect();
        p.push(format!(
            "left behind {new:?} (a_file.obj intact: {})",
            run.a_file_intact
        ));
    }
    p
}

#[test]
fn every_malformed_input_and_bad_argument_is_refused_in_one_line() {
    let all = cases();
    // The corpus and tables agree: every table file exists, every KNOWN entry is a case,
    // and no case is listed twice.
    for table in TABLES {
        for (file, _) in table.files {
            let path = corpus().join(table.dir).join(file);
            assert!(
                path.exists(),
                "{} is missing from the corpus",
                path.display()
            );
        }
    }
    let mut seen = BTreeSet::new();
    for c in &all {
        assert!(
            seen.insert(c.args.as_str()),
            "case listed twice: {}",
            c.args
        );
    }
    for (args, _) in KNOWN {
        assert!(seen.contains(args), "KNOWN entry matches no case: {args}");
    }
    assert!(all.len() >= 150, "only {} cases", all.len());

    let root = scratch("cases");
    let fixture_dir = root.join("fixtures");
    std::fs::create_dir_all(&fixture_dir).unwrap();
    std::fs::create_dir_all(root.join("logs")).unwrap();
    fixtures(&fixture_dir);
    let corpus_before = listing(&corpus());
    let fixtures_before = listing(&fixture_dir);

    let run_known = std::env::var_os("WEFT_MALFORMED_KNOWN").is_some();
    let todo: Vec<(usize, &Case, Option<&str>)> = all
        .iter()
        .enumerate()
        .filter_map(|(i, c)| {
            let known = KNOWN
                .iter()
                .find(|(a, _)| *a == c.args)
                .map(|(_, why)| *why);
            (known.is_none() || run_known).then_some((i, c, known))
        })
        .collect();
    let next = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::new());
    let fixed = Mutex::new(Vec::new());
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get().clamp(2, 4));
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(&(i, case, known)) = todo.get(k) else {
                    break;
                };
                let r = run(case, i, &root, &fixture_dir);
                let p = problems(case, &r);
                match (known, p.is_empty()) {
                    (Some(_), true) => fixed.lock().unwrap().push(case.args.clone()),
                    (None, false) => failures.lock().unwrap().push(format!(
                        "weft {}\n    {}\n    stderr: {}\n    stdout: {}",
                        case.args,
                        p.join("; "),
                        r.stderr.trim_end().replace('\n', "\n            "),
                        r.stdout.chars().take(300).collect::<String>().trim_end()
                    )),
                    _ => {}
                }
            });
        }
    });

    assert_eq!(
        listing(&corpus()),
        corpus_before,
        "a case changed the corpus"
    );
    assert_eq!(
        listing(&fixture_dir),
        fixtures_before,
        "a case changed the fixtures"
    );
    let fixed = fixed.into_inner().unwrap();
    if !fixed.is_empty() {
        eprintln!("KNOWN cases that pass by now (remove them from KNOWN):");
        for f in &fixed {
            eprintln!("  {f}");
        }
    }
    let mut failures = failures.into_inner().unwrap();
    failures.sort();
    assert!(
        failures.is_empty(),
        "{} of {} cases ({} known and skipped) did not fail as they must:\n{}",
        failures.len(),
        all.len(),
        KNOWN.len(),
        failures.join("\n")
    );
    if run_known {
        eprintln!(
            "{} cases, the {} known ones run too: {} of those pass by now",
            all.len(),
            KNOWN.len(),
            fixed.len()
        );
    } else {
        eprintln!(
            "{} cases: {} refused as they must, {} known and skipped",
            all.len(),
            todo.len(),
            all.len() - todo.len()
        );
    }
}
