//! What every fuzz target shares: a counting global allocator and [`bounded`], which
//! runs a reader and aborts the moment the bytes it holds live exceed a bound.
//!
//! The claim checked is "no reader allocates more than a small multiple of its input":
//! memory follows the bytes present, never a count or a size a header claims. The bound
//! is on the *live* bytes (allocated and not yet freed) during the call, measured from
//! what was live when it started, so memory the reader returns counts until it is
//! dropped. The check runs inside the allocator, before the allocation is made, so a
//! violation aborts with the stack of the allocation that crossed the bound (libFuzzer
//! reports the abort as a crash and saves the input).
//!
//! Bounds (see docs/fuzzing.md): [`linear_bound`] for readers of plain bytes,
//! [`inflating_bound`] for `.npz` readers, whose deflated members may legitimately
//! expand up to [`MAX_DEFLATE_RATIO`] times.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write as _;
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

pub use weft_mesh::io::npz::MAX_DEFLATE_RATIO;

/// Bytes every bound allows beyond its multiple of the input: the fixed costs of a
/// reader (error messages, small tables, a zip reader's buffers), whatever the input.
pub const SLACK: usize = 8 << 20;

/// The bound for readers of plain (uncompressed) bytes: 64 × the input + [`SLACK`].
pub fn linear_bound(input: usize) -> usize {
    input.saturating_mul(64).saturating_add(SLACK)
}

/// The bound for `.npz` readers: 16 × what the archive can inflate to (at most
/// [`MAX_DEFLATE_RATIO`] × its bytes + 64 per member's worth of slack, the reader's own
/// limit) + [`SLACK`]. 16 covers the member's bytes as read (a growing buffer up to 2×),
/// a Fortran-to-C copy (1×), the widest conversion (`|u1` or `|b1` to `i64`, 8×) and the
/// caller's use of the result.
///
/// Plus [`ZIP_DIRECTORY`]: a fixed cost of the zip crate, not a multiple of anything.
pub fn inflating_bound(input: usize) -> usize {
    let inflated = input
        .saturating_mul(MAX_DEFLATE_RATIO as usize)
        .saturating_add(64);
    inflated
        .saturating_mul(16)
        .saturating_add(SLACK)
        .saturating_add(ZIP_DIRECTORY)
}

/// What zip 2.6.1 may allocate up front for an archive's central directory, whatever the
/// archive's length: `ZipArchive::new` reserves room for the member count of the end
/// record (a 16-bit field, so at most 65 535 entries of 208 bytes, 13.6 MB) when the
/// record's directory offset is at least that count, and an end record that says "no
/// members in all" skips the check that the offset lies inside the file. A 34-byte
/// archive (`PK\x05\x06`, 64 663 members on this disk, 0 in all, offset 0x05495000)
/// makes it reserve 13.4 MB (found by the `read_npz` target; see docs/fuzzing.md).
pub const ZIP_DIRECTORY: usize = 14 << 20;

/// The counting allocator: [`System`] with a tally of live bytes.
pub struct Counting;

/// Bytes allocated and not yet freed, by anything in the process.
static LIVE: AtomicUsize = AtomicUsize::new(0);
/// The most bytes live since [`bounded`] started, as an excess over its base.
static PEAK: AtomicUsize = AtomicUsize::new(0);
/// Live bytes when [`bounded`] started.
static BASE: AtomicUsize = AtomicUsize::new(0);
/// The bound on live bytes above [`BASE`]; `usize::MAX` when no call is watched.
static BOUND: AtomicUsize = AtomicUsize::new(usize::MAX);
/// The input's length, for the message.
static INPUT: AtomicUsize = AtomicUsize::new(0);

#[global_allocator]
static ALLOCATOR: Counting = Counting;

impl Counting {
    /// Records `n` more live bytes; aborts if that crosses the bound. Called before the
    /// allocation is made, so an absurd request never reaches the system allocator.
    #[inline]
    fn grow(n: usize) {
        let now = LIVE.fetch_add(n, Relaxed).wrapping_add(n);
        let bound = BOUND.load(Relaxed);
        if bound == usize::MAX {
            return;
        }
        let over = now.saturating_sub(BASE.load(Relaxed));
        PEAK.fetch_max(over, Relaxed);
        if over > bound {
            exceeded(over, n, bound);
        }
    }

    #[inline]
    fn shrink(n: usize) {
        LIVE.fetch_sub(n, Relaxed);
    }
}

/// Writes why, without allocating (we are inside the allocator), and aborts.
#[cold]
fn exceeded(live: usize, request: usize, bound: usize) -> ! {
    BOUND.store(usize::MAX, Relaxed);
    let mut buf = [0u8; 256];
    let mut w = &mut buf[..];
    let _ = write!(
        w,
        "\nweft-fuzz: memory bound exceeded: {live} bytes live (after a request of {request}) \
         for an input of {} bytes; the bound is {bound}\n",
        INPUT.load(Relaxed)
    );
    let left = w.len();
    let used = buf.len() - left;
    let _ = std::io::stderr().write_all(&buf[..used]);
    std::process::abort();
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        Self::grow(layout.size());
        let p = System.alloc(layout);
        if p.is_null() {
            Self::shrink(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        Self::grow(layout.size());
        let p = System.alloc_zeroed(layout);
        if p.is_null() {
            Self::shrink(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout);
        Self::shrink(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = layout.size();
        if new_size > old {
            Self::grow(new_size - old);
        }
        let p = System.realloc(ptr, layout, new_size);
        if p.is_null() {
            if new_size > old {
                Self::shrink(new_size - old);
            }
        } else if new_size < old {
            Self::shrink(old - new_size);
        }
        p
    }
}

/// Runs `read` on an input of `input` bytes and aborts if, at any moment during it, the
/// bytes live exceed those live at the start by more than `bound`. Returns what `read`
/// returned and the peak excess it reached.
///
/// One call at a time (the fuzz targets run one input at a time); allocations of other
/// threads during the call count too.
pub fn bounded<R>(input: usize, bound: usize, read: impl FnOnce() -> R) -> (R, usize) {
    // A panic is the finding: stop counting before the panic hook (libfuzzer-sys's, which
    // prints the message and a backtrace, then aborts) allocates for its report.
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let report = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if let (Some(at), Some(allowed)) = (info.location(), ALLOWED_PANICS.get()) {
                if allowed.iter().any(|a| at.file().contains(a)) {
                    // Unwinds to the reader's own `catch_unwind`; one that escapes it is
                    // still caught by libfuzzer-sys, which aborts.
                    return;
                }
            }
            BOUND.store(usize::MAX, Relaxed);
            report(info);
        }));
    });
    INPUT.store(input, Relaxed);
    BASE.store(LIVE.load(Relaxed), Relaxed);
    PEAK.store(0, Relaxed);
    BOUND.store(bound, Relaxed);
    let out = read();
    BOUND.store(usize::MAX, Relaxed);
    (out, PEAK.load(Relaxed))
}

static ALLOWED_PANICS: std::sync::OnceLock<&'static [&'static str]> = std::sync::OnceLock::new();

/// Panics raised in source files whose path contains one of `files` are let through to a
/// `catch_unwind` in the code under test instead of aborting at once (libfuzzer-sys's
/// panic hook aborts on every panic, even one that would be caught). For third-party
/// code that panics on bad input where weft catches the panic and reports an error; a
/// panic that is not caught still aborts. Call before the first [`bounded`].
///
/// With `WEFT_FUZZ_STRICT` set in the environment every panic aborts (to reproduce or
/// minimise an input that makes the third-party code panic).
pub fn allow_caught_panics_from(files: &'static [&'static str]) {
    if std::env::var_os("WEFT_FUZZ_STRICT").is_none() {
        let _ = ALLOWED_PANICS.set(files);
    }
}

/// Bytes live now (for tests of the allocator itself).
pub fn live() -> usize {
    LIVE.load(Relaxed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_peak_follows_live_bytes() {
        let (v, peak) = bounded(10, 1 << 30, || vec![0u8; 1 << 20]);
        assert!(peak >= 1 << 20, "{peak}");
        drop(v);
        let ((), peak) = bounded(10, 1 << 30, || {
            let mut v: Vec<u64> = Vec::new();
            for i in 0..1000 {
                v.push(i);
            }
        });
        assert!((8000..=64_000).contains(&peak), "{peak}");
    }
}

/// The Multilevel configuration the checkpoint target loads records into: every width
/// and depth 1 or 2, so a whole valid checkpoint is a few kilobytes (the `cpu` preset's
/// are megabytes, beyond what a fuzzer mutates well) while the record has the same
/// parameter names and structure as a real run's.
#[cfg(feature = "burn")]
pub fn tiny_multilevel() -> weft_models::multilevel::MultilevelConfig {
    weft_models::multilevel::MultilevelConfig::new()
        .with_joints(2)
        .with_feature_width(2)
        .with_gg_widths(vec![2])
        .with_gg_heads(1)
        .with_gs_hidden(vec![2])
        .with_bs_hidden(vec![2])
        .with_nystrom_landmarks(2)
        .with_body_samples(2)
        .with_history(1)
        .with_t1_layers(1)
        .with_t2_layers(1)
        .with_mp_submodules(1)
        .with_mp_levels(1)
        .with_mp_channels(2)
        .with_mp_heads(1)
        .with_out_heads(1)
}
