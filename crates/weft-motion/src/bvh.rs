//! BVH (Biovision Hierarchy) files of any skeleton: parsing, evaluation and writing.
//!
//! A BVH file is a `HIERARCHY` of joints — `ROOT`/`JOINT` blocks with an `OFFSET` from
//! the parent and a list of `CHANNELS`, leaves closed by `End Site` blocks — followed by
//! a `MOTION` section: `Frames: N`, `Frame Time: seconds`, then one line per frame with
//! one number per channel, in the order the joints appear in the hierarchy.
//!
//! Conventions this module implements (those of the Biovision format and of the
//! readers of Blender, MotionBuilder and the CMU conversions):
//!
//! - **Rotation channels compose in the order listed, the first outermost.** For
//!   `CHANNELS 3 Zrotation Xrotation Yrotation` the joint's rotation is
//!   `R = Rz(z)·Rx(x)·Ry(y)`: a point of the joint's frame is turned about Y first, then
//!   X, then Z (parent-fixed axes), the same as Z, then the new X, then the newest Y
//!   (moving axes). Angles are in degrees. Any order and any subset of axes is read.
//! - **Position channels replace the offset** on the axes they name (the root's
//!   `Xposition Yposition Zposition` give its absolute place); other axes keep OFFSET.
//! - The joint's transform in its parent's frame is `translate(offset) · R`, so the rest
//!   pose (all channels zero) has every joint frame aligned with the world.
//!
//! The parser never panics: every error names the file and line and says what was
//! expected. It checks the declared frame count against the bytes that follow before
//! allocating, so a corrupt `Frames:` line cannot exhaust memory.

use std::collections::HashSet;
use std::fmt::Write as _;
use std::io;
use std::path::Path;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use super::error::MotionError;
use super::rot::about_axis;

/// One channel of a BVH joint: a translation or a rotation (degrees) along an axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    /// Translation along X.
    Xposition,
    /// Translation along Y.
    Yposition,
    /// Translation along Z.
    Zposition,
    /// Rotation about X, degrees.
    Xrotation,
    /// Rotation about Y, degrees.
    Yrotation,
    /// Rotation about Z, degrees.
    Zrotation,
}

impl Channel {
    /// Reads a channel name (any case, as some exporters lower-case them).
    pub fn parse(name: &str) -> Option<Channel> {
        Some(match name.to_ascii_lowercase().as_str() {
            "xposition" => Channel::Xposition,
            "yposition" => Channel::Yposition,
            "zposition" => Channel::Zposition,
            "xrotation" => Channel::Xrotation,
            "yrotation" => Channel::Yrotation,
            "zrotation" => Channel::Zrotation,
            _ => return None,
        })
    }

    /// The name written in files.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Xposition => "Xposition",
            Channel::Yposition => "Yposition",
            Channel::Zposition => "Zposition",
            Channel::Xrotation => "Xrotation",
            Channel::Yrotation => "Yrotation",
            Channel::Zrotation => "Zrotation",
        }
    }

    /// The axis: 0 = X, 1 = Y, 2 = Z.
    pub fn axis(self) -> usize {
        match self {
            Channel::Xposition | Channel::Xrotation => 0,
            Channel::Yposition | Channel::Yrotation => 1,
            Channel::Zposition | Channel::Zrotation => 2,
        }
    }

    /// Whether this is a rotation channel.
    pub fn is_rotation(self) -> bool {
        matches!(
            self,
            Channel::Xrotation | Channel::Yrotation | Channel::Zrotation
        )
    }
}

/// A joint of a BVH skeleton.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhJoint {
    /// The name as written after `ROOT`/`JOINT` (the rest of that line, trimmed).
    pub name: String,
    /// The parent's index in [`Bvh::joints`], `None` for a root. Parents come first.
    pub parent: Option<usize>,
    /// Offset from the parent joint in the rest pose, in the file's units.
    pub offset: [f64; 3],
    /// The joint's channels in file order.
    pub channels: Vec<Channel>,
    /// Offsets of the joint's `End Site` blocks (bone ends without a joint).
    pub end_sites: Vec<[f64; 3]>,
    /// 1-based line of the joint's `ROOT`/`JOINT` keyword, for messages.
    pub line: usize,
}

/// Where a BVH skeleton's joints and end sites are in its rest pose.
#[derive(Clone, Debug, PartialEq)]
pub struct RestPositions {
    /// One position per joint, in [`Bvh::joints`] order.
    pub joints: Vec<Vector3<f64>>,
    /// `(joint, position)` of every end site.
    pub end_sites: Vec<(usize, Vector3<f64>)>,
}

/// A parsed BVH file: the skeleton and the channel values of every frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    joints: Vec<BvhJoint>,
    /// Index of each joint's first value within a frame.
    first_channel: Vec<usize>,
    channel_count: usize,
    frame_time: f64,
    frame_count: usize,
    /// `frame_count × channel_count` values, frame-major.
    values: Vec<f64>,
}

impl Bvh {
    /// A BVH from its parts; fails when there are no joints, a parent does not precede
    /// its child, the frame time is not positive, or `values` is not one value per
    /// channel per frame.
    pub fn new(
        joints: Vec<BvhJoint>,
        frame_time: f64,
        values: Vec<f64>,
    ) -> Result<Self, MotionError> {
        if joints.is_empty() {
            return Err(MotionError::Invalid("a BVH skeleton needs a joint".into()));
        }
        for (j, joint) in joints.iter().enumerate() {
            if joint.parent.is_some_and(|p| p >= j) {
                return Err(MotionError::Invalid(format!(
                    "BVH joint {j} ({}) comes before its parent",
                    joint.name
                )));
            }
        }
        if !(frame_time.is_finite() && frame_time > 0.0) {
            return Err(MotionError::Invalid(format!(
                "BVH frame time {frame_time}; expected seconds above 0"
            )));
        }
        let mut first_channel = Vec::with_capacity(joints.len());
        let mut channel_count = 0;
        for joint in &joints {
            first_channel.push(channel_count);
            channel_count += joint.channels.len();
        }
        let frame_count = values.len().checked_div(channel_count).unwrap_or(0);
        if channel_count == 0 || values.len() != frame_count * channel_count {
            return Err(MotionError::Invalid(format!(
                "{} BVH values for {channel_count} channels; expected a whole number of frames of at least one channel",
                values.len()
            )));
        }
        Ok(Bvh {
            joints,
            first_channel,
            channel_count,
            frame_time,
            frame_count,
            values,
        })
    }

    /// Reads and parses a BVH file.
    pub fn read(path: &Path) -> Result<Self, MotionError> {
        let bytes = weft_mesh::io::read_input(path).map_err(|e| MotionError::io(path, e))?;
        Bvh::parse(&bytes, path)
    }

    /// Parses the bytes of a BVH file; `path` only names the file in errors.
    pub fn parse(bytes: &[u8], path: &Path) -> Result<Self, MotionError> {
        let text = std::str::from_utf8(bytes).map_err(|e| {
            let line = 1 + bytes[..e.valid_up_to()]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            MotionError::bvh(path, line, "not UTF-8 text; a BVH file is plain text")
        })?;
        Parser {
            cursor: Cursor {
                rest: text,
                line: 1,
            },
            path,
        }
        .parse()
    }

    /// The joints, parents before children, in file order.
    pub fn joints(&self) -> &[BvhJoint] {
        &self.joints
    }

    /// The index of the joint named exactly `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Channels per frame, all joints together.
    pub fn channel_count(&self) -> usize {
        self.channel_count
    }

    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.frame_count
    }

    /// Seconds per frame, as written after `Frame Time:`.
    pub fn frame_time(&self) -> f64 {
        self.frame_time
    }

    /// Frames per second, `1 / frame_time`, snapped to the nearest whole number when
    /// within a relative 10⁻⁴ of it: files round the frame time (`0.033333` for 30 fps)
    /// and the round number is what the capture ran at.
    pub fn fps(&self) -> f64 {
        let fps = 1.0 / self.frame_time;
        let round = fps.round();
        if round > 0.0 && (fps - round).abs() <= 1e-4 * fps {
            round
        } else {
            fps
        }
    }

    /// The channel values of frame `frame` (`channel_count` numbers).
    ///
    /// # Panics
    /// When `frame >= frame_count()`.
    pub fn frame(&self, frame: usize) -> &[f64] {
        &self.values[frame * self.channel_count..(frame + 1) * self.channel_count]
    }

    /// Joint `joint`'s transform relative to its parent at frame `frame`:
    /// `translate(offset, position channels replacing their axes) · R(rotation channels)`.
    /// Translations are in the file's units.
    pub fn local_transform(&self, frame: usize, joint: usize) -> Isometry3<f64> {
        let j = &self.joints[joint];
        let values = &self.frame(frame)[self.first_channel[joint]..][..j.channels.len()];
        let mut t = j.offset;
        let mut r = UnitQuaternion::identity();
        for (&c, &v) in j.channels.iter().zip(values) {
            if c.is_rotation() {
                r *= about_axis(c.axis(), v.to_radians());
            } else {
                t[c.axis()] = v;
            }
        }
        Isometry3::from_parts(Translation3::new(t[0], t[1], t[2]), r)
    }

    /// Every joint's transform in the world (the file's frame and units) at `frame`.
    pub fn global_transforms(&self, frame: usize) -> Vec<Isometry3<f64>> {
        let mut out: Vec<Isometry3<f64>> = Vec::with_capacity(self.joints.len());
        for (j, joint) in self.joints.iter().enumerate() {
            let local = self.local_transform(frame, j);
            out.push(match joint.parent {
                Some(p) => out[p] * local,
                None => local,
            });
        }
        out
    }

    /// Rest-pose (all channels zero, offsets only) positions of the joints and the end
    /// sites, in the file's frame and units.
    pub fn rest_positions(&self) -> RestPositions {
        let mut joints: Vec<Vector3<f64>> = Vec::with_capacity(self.joints.len());
        let mut end_sites = Vec::new();
        for (j, joint) in self.joints.iter().enumerate() {
            let base = joint.parent.map_or_else(Vector3::zeros, |p| joints[p]);
            let here = base + Vector3::from(joint.offset);
            for e in &joint.end_sites {
                end_sites.push((j, here + Vector3::from(*e)));
            }
            joints.push(here);
        }
        RestPositions { joints, end_sites }
    }

    /// Writes the file text: tab-indented hierarchy, one line per frame, numbers with
    /// six decimals (trailing zeros dropped) and the frame time in full precision so the
    /// frame rate survives a round trip.
    pub fn write_to(&self, w: &mut dyn io::Write) -> io::Result<()> {
        let mut s = String::from("HIERARCHY\n");
        let mut children = vec![Vec::new(); self.joints.len()];
        let mut roots = Vec::new();
        for (j, joint) in self.joints.iter().enumerate() {
            match joint.parent {
                Some(p) => children[p].push(j),
                None => roots.push(j),
            }
        }
        // The file lists joints depth first, and frame values follow that order, which
        // need not be the order of `joints` (SMPL's is not depth first).
        let mut order = Vec::with_capacity(self.joints.len());
        for r in roots {
            self.write_tree(&mut s, r, &children, &mut order);
        }
        let _ = writeln!(s, "MOTION\nFrames: {}", self.frame_count);
        let _ = writeln!(s, "Frame Time: {}", self.frame_time);
        w.write_all(s.as_bytes())?;
        let mut line = String::new();
        for f in 0..self.frame_count {
            line.clear();
            let frame = self.frame(f);
            for &j in &order {
                let start = self.first_channel[j];
                for &v in &frame[start..start + self.joints[j].channels.len()] {
                    if !line.is_empty() {
                        line.push(' ');
                    }
                    push_number(&mut line, v);
                }
            }
            line.push('\n');
            w.write_all(line.as_bytes())?;
        }
        Ok(())
    }

    /// Writes the file atomically (see [`weft_mesh::io::write_atomic`]).
    pub fn write(&self, path: &Path) -> Result<(), MotionError> {
        weft_mesh::io::write_atomic(path, |w| self.write_to(w))
            .map_err(|e| MotionError::io(path, e))
    }

    /// Writes the block of joint `root` and of everything below it, depth first, and
    /// appends the joints to `order` as it goes. Iterative, so a hierarchy as deep as the
    /// file is long needs no deep call stack; indentation stops growing past
    /// [`MAX_INDENT`] levels, so the text stays linear in the number of joints.
    fn write_tree(
        &self,
        s: &mut String,
        root: usize,
        children: &[Vec<usize>],
        order: &mut Vec<usize>,
    ) {
        // (joint, depth, whether its block is open): a joint is visited twice, once to
        // open its block and list its children, once to close it.
        let mut stack = vec![(root, 0usize, false)];
        while let Some((j, depth, opened)) = stack.pop() {
            let joint = &self.joints[j];
            let pad = "\t".repeat(depth.min(MAX_INDENT));
            if opened {
                for e in &joint.end_sites {
                    let _ = writeln!(s, "{pad}\tEnd Site\n{pad}\t{{");
                    write_offset(s, &format!("{pad}\t"), *e);
                    let _ = writeln!(s, "{pad}\t}}");
                }
                let _ = writeln!(s, "{pad}}}");
                continue;
            }
            order.push(j);
            let keyword = if joint.parent.is_none() {
                "ROOT"
            } else {
                "JOINT"
            };
            let _ = writeln!(s, "{pad}{keyword} {}\n{pad}{{", joint.name);
            write_offset(s, &pad, joint.offset);
            let _ = write!(s, "{pad}\tCHANNELS {}", joint.channels.len());
            for c in &joint.channels {
                let _ = write!(s, " {}", c.name());
            }
            s.push('\n');
            stack.push((j, depth, true));
            stack.extend(children[j].iter().rev().map(|&c| (c, depth + 1, false)));
        }
    }
}

/// Deepest indentation [`Bvh::write_to`] writes, in tabs: deeper joints are written at
/// this depth (readers ignore indentation; a 100 000-joint chain would otherwise be
/// gigabytes of tabs).
const MAX_INDENT: usize = 32;

fn write_offset(s: &mut String, pad: &str, o: [f64; 3]) {
    let _ = write!(s, "{pad}\tOFFSET");
    for x in o {
        s.push(' ');
        push_number(s, x);
    }
    s.push('\n');
}

/// Six decimals without trailing zeros: `0.09` rather than `0.09000000000000002` or
/// `0.090000`, and `0` rather than `-0`.
fn push_number(s: &mut String, x: f64) {
    let start = s.len();
    let _ = write!(s, "{x:.6}");
    if s[start..].contains('.') {
        let trimmed = s[start..].trim_end_matches('0').trim_end_matches('.').len();
        s.truncate(start + trimmed);
    }
    if &s[start..] == "-0" {
        s.truncate(start);
        s.push('0');
    }
}

/// Reads tokens (whitespace-separated words, braces on their own) and lines, counting
/// lines as it goes.
struct Cursor<'a> {
    rest: &'a str,
    /// 1-based line of the first byte of `rest`.
    line: usize,
}

impl<'a> Cursor<'a> {
    /// Skips whitespace (counting newlines).
    fn skip_space(&mut self) {
        let trimmed = self.rest.trim_start();
        let skipped = &self.rest[..self.rest.len() - trimmed.len()];
        self.line += skipped.bytes().filter(|&b| b == b'\n').count();
        self.rest = trimmed;
    }

    /// The next token and its line, `None` at the end.
    fn token(&mut self) -> Option<(&'a str, usize)> {
        self.skip_space();
        if self.rest.is_empty() {
            return None;
        }
        let end = if self.rest.starts_with(['{', '}']) {
            1
        } else {
            self.rest
                .find(|c: char| c.is_whitespace() || c == '{' || c == '}')
                .unwrap_or(self.rest.len())
        };
        let (tok, rest) = self.rest.split_at(end);
        self.rest = rest;
        Some((tok, self.line))
    }

    /// The rest of the current line (without the newline), consuming the newline.
    fn rest_of_line(&mut self) -> (&'a str, usize) {
        let line = self.line;
        let text = match self.rest.find('\n') {
            Some(end) => {
                let text = &self.rest[..end];
                self.rest = &self.rest[end + 1..];
                self.line += 1;
                text
            }
            None => std::mem::take(&mut self.rest),
        };
        (text.trim_end_matches('\r'), line)
    }
}

struct Parser<'a, 'p> {
    cursor: Cursor<'a>,
    path: &'p Path,
}

/// A joint whose block is open.
struct Open {
    index: usize,
    has_offset: bool,
}

impl Parser<'_, '_> {
    fn err(&self, line: usize, message: impl Into<String>) -> MotionError {
        MotionError::bvh(self.path, line, message)
    }

    fn expect(&mut self, what: &str, after: &str) -> Result<usize, MotionError> {
        match self.cursor.token() {
            Some((t, line)) if t == what => Ok(line),
            Some((t, line)) => {
                Err(self.err(line, format!("expected '{what}' {after}, found '{t}'")))
            }
            None => Err(self.truncated(&format!("'{what}' {after}"))),
        }
    }

    fn truncated(&self, expected: &str) -> MotionError {
        self.err(
            self.cursor.line,
            format!("the file ends here, truncated; expected {expected}"),
        )
    }

    fn number(&mut self, what: &str) -> Result<f64, MotionError> {
        match self.cursor.token() {
            Some((t, line)) => match t.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(self.err(
                    line,
                    format!("expected a finite number for {what}, found '{t}'"),
                )),
            },
            None => Err(self.truncated(&format!("a number for {what}"))),
        }
    }

    fn offset(&mut self, whose: &str) -> Result<[f64; 3], MotionError> {
        let what = format!("the OFFSET of {whose}");
        Ok([
            self.number(&what)?,
            self.number(&what)?,
            self.number(&what)?,
        ])
    }

    fn parse(mut self) -> Result<Bvh, MotionError> {
        self.expect("HIERARCHY", "at the start of a BVH file")?;
        let mut joints: Vec<BvhJoint> = Vec::new();
        // Names seen so far, so that checking a new one is one lookup, not a scan of
        // every joint before it (which made 100 000 joints take half a minute).
        let mut names: HashSet<&str> = HashSet::new();
        let mut stack: Vec<Open> = Vec::new();
        loop {
            let Some((tok, line)) = self.cursor.token() else {
                return Err(match stack.last() {
                    Some(o) => self.truncated(&format!(
                        "'}}' closing joint '{}' (line {})",
                        joints[o.index].name, joints[o.index].line
                    )),
                    None => self.truncated("ROOT or MOTION"),
                });
            };
            match tok {
                "ROOT" | "JOINT" => {
                    let parent = stack.last().map(|o| o.index);
                    if tok == "ROOT" && parent.is_some() {
                        return Err(self.err(line, "ROOT inside another joint's block; expected JOINT"));
                    }
                    if tok == "JOINT" && parent.is_none() {
                        return Err(self.err(line, "JOINT outside any ROOT block"));
                    }
                    let (rest, _) = self.cursor.rest_of_line();
                    let mut name = rest.trim();
                    let brace_on_line = name.ends_with('{');
                    name = name.trim_end_matches('{').trim_end();
                    if name.is_empty() {
                        return Err(self.err(line, format!("{tok} without a joint name")));
                    }
                    // `ROOT a{ {`: a name ending in '{' would be written back as an
                    // opening brace (found by fuzzing, docs/fuzzing.md).
                    if name.ends_with('{') {
                        return Err(self.err(line, format!("joint name '{name}' ends with '{{'; expected a name, then one '{{' opening the joint's block")));
                    }
                    if !names.insert(name) {
                        return Err(self.err(line, format!("a second joint named '{name}'; BVH joint names must be unique")));
                    }
                    if !brace_on_line {
                        self.expect("{", &format!("after {tok} {name}"))?;
                    }
                    stack.push(Open {
                        index: joints.len(),
                        has_offset: false,
                    });
                    joints.push(BvhJoint {
                        name: name.to_owned(),
                        parent,
                        offset: [0.0; 3],
                        channels: Vec::new(),
                        end_sites: Vec::new(),
                        line,
                    });
                }
                "End" => {
                    let Some(top) = stack.last().map(|o| o.index) else {
                        return Err(self.err(line, "End Site outside any joint"));
                    };
                    self.expect("Site", "after End")?;
                    self.expect("{", "after End Site")?;
                    self.expect("OFFSET", "in an End Site block")?;
                    let whose = format!("an End Site of '{}'", joints[top].name);
                    let o = self.offset(&whose)?;
                    self.expect("}", &format!("closing {whose}"))?;
                    joints[top].end_sites.push(o);
                }
                "OFFSET" => {
                    let Some(top) = stack.last_mut() else {
                        return Err(self.err(line, "OFFSET outside any joint"));
                    };
                    if std::mem::replace(&mut top.has_offset, true) {
                        return Err(self.err(line, "a second OFFSET for one joint"));
                    }
                    let index = top.index;
                    let whose = format!("'{}'", joints[index].name);
                    joints[index].offset = self.offset(&whose)?;
                }
                "CHANNELS" => {
                    let Some(top) = stack.last().map(|o| o.index) else {
                        return Err(self.err(line, "CHANNELS outside any joint"));
                    };
                    if !joints[top].channels.is_empty() {
                        return Err(self.err(line, "a second CHANNELS line for one joint"));
                    }
                    let name = joints[top].name.clone();
                    let n = match self.cursor.token() {
                        Some((t, l)) => t.parse::<usize>().ok().filter(|&n| n <= 6).ok_or_else(|| {
                            self.err(l, format!("expected a channel count from 0 to 6 for '{name}', found '{t}'"))
                        })?,
                        None => return Err(self.truncated("a channel count")),
                    };
                    let mut channels = Vec::with_capacity(n);
                    for k in 0..n {
                        match self.cursor.token() {
                            Some((t, l)) => match Channel::parse(t) {
                                Some(c) => {
                                    if !c.is_rotation() && channels.contains(&c) {
                                        return Err(self.err(l, format!("'{name}' lists {} twice", c.name())));
                                    }
                                    channels.push(c);
                                }
                                None => {
                                    return Err(self.err(l, format!(
                                        "CHANNELS of '{name}' declares {n} channels but channel {} is '{t}'; expected Xposition, Yposition, Zposition, Xrotation, Yrotation or Zrotation",
                                        k + 1
                                    )))
                                }
                            },
                            None => return Err(self.truncated(&format!("{} more channel names for '{name}'", n - k))),
                        }
                    }
                    joints[top].channels = channels;
                }
                "}" => {
                    let Some(open) = stack.pop() else {
                        return Err(self.err(line, "'}' without an open joint block"));
                    };
                    if !open.has_offset {
                        let j = &joints[open.index];
                        return Err(self.err(j.line, format!("joint '{}' has no OFFSET", j.name)));
                    }
                }
                "MOTION" => {
                    if let Some(o) = stack.last() {
                        let j = &joints[o.index];
                        return Err(self.err(line, format!(
                            "MOTION before the block of joint '{}' (line {}) is closed; a '}}' is missing",
                            j.name, j.line
                        )));
                    }
                    if joints.is_empty() {
                        return Err(self.err(line, "MOTION without a ROOT joint before it"));
                    }
                    return self.motion(joints, line);
                }
                other => {
                    return Err(self.err(line, format!(
                        "unexpected '{other}'; expected ROOT, JOINT, End Site, OFFSET, CHANNELS, '}}' or MOTION"
                    )))
                }
            }
        }
    }

    fn motion(mut self, joints: Vec<BvhJoint>, motion_line: usize) -> Result<Bvh, MotionError> {
        let channels: usize = joints.iter().map(|j| j.channels.len()).sum();
        if channels == 0 {
            return Err(self.err(
                motion_line,
                "no joint has CHANNELS; a BVH motion needs at least one channel",
            ));
        }
        let frames_line = self.expect("Frames:", "after MOTION")?;
        let frames = match self.cursor.token() {
            Some((t, l)) => t.parse::<usize>().map_err(|_| {
                self.err(
                    l,
                    format!("expected a whole number of frames after 'Frames:', found '{t}'"),
                )
            })?,
            None => return Err(self.truncated("the number of frames")),
        };
        self.expect("Frame", "after the frame count")?;
        self.expect("Time:", "after 'Frame'")?;
        let time_line = self.cursor.line;
        let frame_time = self.number("the frame time")?;
        if frame_time <= 0.0 {
            return Err(self.err(
                time_line,
                format!("frame time {frame_time}; expected seconds above 0"),
            ));
        }
        let (rest, l) = self.cursor.rest_of_line();
        if !rest.trim().is_empty() {
            return Err(self.err(
                l,
                format!("unexpected '{}' after the frame time", rest.trim()),
            ));
        }
        // Every value takes at least one character and one separator, so a frame count
        // the remaining bytes cannot hold is refused before anything is allocated.
        let available = self.cursor.rest.len() + 1;
        let needed = frames.checked_mul(channels).and_then(|v| v.checked_mul(2));
        if !matches!(needed, Some(n) if n <= available) {
            return Err(self.err(frames_line, format!(
                "'Frames: {frames}' declares {frames} frames of {channels} channels, more than the {} bytes that follow can hold; the file is truncated or the count is wrong",
                available - 1
            )));
        }
        let mut values = Vec::with_capacity(frames * channels);
        let mut read = 0;
        loop {
            if self.cursor.rest.is_empty() {
                break;
            }
            let (text, line) = self.cursor.rest_of_line();
            if text.trim().is_empty() {
                continue;
            }
            if read == frames {
                return Err(self.err(
                    line,
                    format!(
                    "more frame lines than the {frames} declared by 'Frames:' (line {frames_line})"
                ),
                ));
            }
            let before = values.len();
            for tok in text.split_whitespace() {
                match tok.parse::<f64>() {
                    Ok(x) if x.is_finite() => values.push(x),
                    _ => {
                        return Err(self.err(
                            line,
                            format!(
                                "frame {}: expected a finite number, found '{tok}'",
                                read + 1
                            ),
                        ))
                    }
                }
                if values.len() - before > channels {
                    break;
                }
            }
            let found = values.len() - before;
            if found != channels {
                let count = if found > channels {
                    format!("more than {channels}")
                } else {
                    found.to_string()
                };
                return Err(self.err(
                    line,
                    format!(
                        "frame {} has {count} values; the CHANNELS declare {channels} per frame",
                        read + 1
                    ),
                ));
            }
            read += 1;
        }
        if read < frames {
            return Err(self.err(self.cursor.line, format!(
                "the file ends after {read} of the {frames} frames declared by 'Frames:' (line {frames_line}); it is truncated"
            )));
        }
        Bvh::new(joints, frame_time, values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TWO_BONES: &str = "HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Leg
  {
    OFFSET 0 -10 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    End Site
    {
      OFFSET 0 -10 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.033333
1 2 3 0 0 0 0 0 0
1 2 3 90 0 0 0 90 0
";

    fn parse(s: &str) -> Result<Bvh, MotionError> {
        Bvh::parse(s.as_bytes(), Path::new("t.bvh"))
    }

    #[test]
    fn parses_hierarchy_and_frames() {
        let b = parse(TWO_BONES).unwrap();
        assert_eq!(b.joints().len(), 2);
        assert_eq!(b.joints()[1].parent, Some(0));
        assert_eq!(b.joints()[1].offset, [0.0, -10.0, 0.0]);
        assert_eq!(b.joints()[1].end_sites, vec![[0.0, -10.0, 0.0]]);
        assert_eq!((b.channel_count(), b.frame_count()), (9, 2));
        assert_eq!(b.fps(), 30.0);
        assert_eq!(b.frame(1)[3], 90.0);
        let rest = b.rest_positions();
        assert_eq!(rest.joints[1], Vector3::new(0.0, -10.0, 0.0));
        assert_eq!(rest.end_sites, vec![(1, Vector3::new(0.0, -20.0, 0.0))]);
    }

    #[test]
    fn channels_compose_in_listed_order() {
        // Frame 1: root Zrot 90 then Xrot 0, Yrot 0; leg Yrotation 90.
        let b = parse(TWO_BONES).unwrap();
        let g = b.global_transforms(1);
        // Root at (1,2,3) turned 90° about Z; the leg hangs 10 below the root in the
        // root's frame, which Z-90° maps to +X.
        let knee = g[1].translation.vector;
        assert!(
            (knee - Vector3::new(11.0, 2.0, 3.0)).norm() < 1e-9,
            "{knee}"
        );
        // Rz(30)·Rx(40)·Ry(50) applied to a vector equals turning about Y, X, then Z.
        let one = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n30 40 50\n";
        let r = parse(one).unwrap().local_transform(0, 0).rotation;
        let v = Vector3::new(0.3, -0.2, 0.9);
        let expected = about_axis(2, 30f64.to_radians())
            * (about_axis(0, 40f64.to_radians()) * (about_axis(1, 50f64.to_radians()) * v));
        assert!((r * v - expected).norm() < 1e-12);
    }

    #[test]
    fn writes_what_it_reads() {
        let b = parse(TWO_BONES).unwrap();
        let mut out = Vec::new();
        b.write_to(&mut out).unwrap();
        let again = Bvh::parse(&out, Path::new("w.bvh")).unwrap();
        assert_eq!(again, b);
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("Frame Time: 0.033333\n"), "{text}");
        assert!(
            text.contains("\tJOINT Leg\n\t{\n\t\tOFFSET 0 -10 0\n"),
            "{text}"
        );
    }

    #[test]
    fn joints_in_any_parent_first_order_are_written_depth_first() {
        let joint = |name: &str, parent, offset| BvhJoint {
            name: name.into(),
            parent,
            offset,
            channels: vec![Channel::Zrotation, Channel::Xrotation],
            end_sites: vec![],
            line: 0,
        };
        // Not depth first: B (a root child) comes before A's child A1.
        let joints = vec![
            joint("R", None, [0.0; 3]),
            joint("A", Some(0), [1.0, 0.0, 0.0]),
            joint("B", Some(0), [-1.0, 0.0, 0.0]),
            joint("A1", Some(1), [0.0, 1.0, 0.0]),
        ];
        let values = vec![10.0, 1.0, 20.0, 2.0, 30.0, 3.0, 40.0, 4.0];
        let b = Bvh::new(joints, 0.5, values).unwrap();
        let mut out = Vec::new();
        b.write_to(&mut out).unwrap();
        let again = Bvh::parse(&out, Path::new("o.bvh")).unwrap();
        let names: Vec<&str> = again.joints().iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names, ["R", "A", "A1", "B"]);
        assert_eq!(
            again.frame(0),
            &[10.0, 1.0, 20.0, 2.0, 40.0, 4.0, 30.0, 3.0]
        );
        let (g, h) = (b.global_transforms(0), again.global_transforms(0));
        for (j, joint) in b.joints().iter().enumerate() {
            let k = again.joint_index(&joint.name).unwrap();
            assert!((g[j].translation.vector - h[k].translation.vector).norm() < 1e-12);
            assert!(g[j].rotation.angle_to(&h[k].rotation) < 1e-12);
        }
    }

    #[test]
    fn accepts_braces_on_the_name_line_and_lower_case_channels() {
        let s = "HIERARCHY\nROOT mixamorig:Hips {\n OFFSET 0 0 0\n CHANNELS 3 xposition yposition zposition\n}\nMOTION\nFrames: 1\r\nFrame Time: 0.5\r\n1 2 3\r\n";
        let b = parse(s).unwrap();
        assert_eq!(b.joints()[0].name, "mixamorig:Hips");
        assert_eq!(b.fps(), 2.0);
    }

    /// TWO_BONES with wider numbers in the frames, so truncating a few bytes of them
    /// passes the frame-count size bound and reaches the line checks.
    fn long_values() -> String {
        let (head, frames) = TWO_BONES.split_at(TWO_BONES.find("1 2 3").unwrap());
        format!("{head}{}", frames.replace(" 0", " 0.000000"))
    }

    fn err(s: &str) -> String {
        parse(s).unwrap_err().to_string()
    }

    #[test]
    fn malformed_files_give_file_and_line() {
        // Truncated inside the hierarchy.
        let cut = &TWO_BONES[..TWO_BONES.find("End Site").unwrap()];
        let e = err(cut);
        assert!(
            e.starts_with("t.bvh:10: the file ends here, truncated"),
            "{e}"
        );
        assert!(e.contains("closing joint 'Leg' (line 6)"), "{e}");
        // Truncated in the frames (values long enough that the size bound passes).
        let long = long_values();
        let e = err(&long[..long.len() - 30]);
        assert!(
            e.starts_with("t.bvh:20: frame 2 has 5 values; the CHANNELS declare 9"),
            "{e}"
        );
        let e = err(long.trim_end().rsplit_once('\n').unwrap().0);
        assert!(e.contains("after 1 of the 2 frames"), "{e}");
        // Bad channel count and channel names.
        let e = err(&TWO_BONES.replace("CHANNELS 3 X", "CHANNELS 4 X"));
        assert!(
            e.starts_with("t.bvh:10: CHANNELS of 'Leg' declares 4 channels but channel 4 is 'End'"),
            "{e}"
        );
        let e = err(&TWO_BONES.replace("CHANNELS 3", "CHANNELS 9"));
        assert!(
            e.starts_with("t.bvh:9: expected a channel count from 0 to 6"),
            "{e}"
        );
        // A frame with one value too many.
        let e = err(&TWO_BONES.replace("0 90 0\n", "0 90 0 7\n"));
        assert!(
            e.starts_with("t.bvh:20: frame 2 has more than 9 values"),
            "{e}"
        );
        // Non-numbers and NaN.
        let e = err(&TWO_BONES.replace("1 2 3 90", "1 2 nan 90"));
        assert!(
            e.starts_with("t.bvh:20: frame 2: expected a finite number, found 'nan'"),
            "{e}"
        );
        let e = err(&TWO_BONES.replace("OFFSET 0 -10 0\n    CH", "OFFSET 0 x 0\n    CH"));
        assert!(
            e.starts_with("t.bvh:8: expected a finite number for the OFFSET of 'Leg'"),
            "{e}"
        );
        // Missing pieces.
        let e = err(&TWO_BONES.replace("HIERARCHY", "HIERARCH"));
        assert!(e.starts_with("t.bvh:1: expected 'HIERARCHY'"), "{e}");
        let e = err(&TWO_BONES.replace("  }\n}\nMOTION", "  }\nMOTION"));
        assert!(
            e.contains("MOTION before the block of joint 'Hips' (line 2) is closed"),
            "{e}"
        );
        let e = err(&TWO_BONES.replace("Frame Time: 0.033333", "Frame Time: 0"));
        assert!(e.starts_with("t.bvh:18: frame time 0"), "{e}");
        let e = err(&TWO_BONES.replace("    OFFSET 0 -10 0\n    CHANNELS", "    CHANNELS"));
        assert!(e.starts_with("t.bvh:6: joint 'Leg' has no OFFSET"), "{e}");
        let e = err(&TWO_BONES.replace("JOINT Leg", "JOINT Hips"));
        assert!(e.contains("a second joint named 'Hips'"), "{e}");
        let e = Bvh::parse(b"HIERARCHY\nROOT \xff\n", Path::new("t.bvh")).unwrap_err();
        assert!(e.to_string().starts_with("t.bvh:2: not UTF-8"), "{e}");
        assert!(err("").contains("truncated"));
    }

    #[test]
    fn absurd_frame_counts_are_refused_before_allocating() {
        let e = err(&TWO_BONES.replace("Frames: 2", "Frames: 99999999999999"));
        assert!(
            e.starts_with("t.bvh:17: 'Frames: 99999999999999' declares"),
            "{e}"
        );
        assert!(e.contains("truncated or the count is wrong"), "{e}");
        let e = err(&TWO_BONES.replace("Frames: 2", "Frames: 18446744073709551615"));
        assert!(e.contains("declares"), "{e}");
        let long = long_values();
        let e = err(&long.replace("Frames: 2", "Frames: 3"));
        assert!(e.contains("after 2 of the 3 frames"), "{e}");
    }

    #[test]
    fn parser_survives_arbitrary_bytes() {
        // Every prefix of a valid file is an error or a file, never a panic.
        for end in 0..TWO_BONES.len() {
            let _ = parse(&TWO_BONES[..end]);
        }
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..2000 {
            let mut bytes = TWO_BONES.as_bytes().to_vec();
            for _ in 0..3 {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let i = (state >> 33) as usize % bytes.len();
                bytes[i] = (state >> 20) as u8;
            }
            let _ = Bvh::parse(&bytes, Path::new("f.bvh"));
        }
    }
}
