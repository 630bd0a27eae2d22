//! Mutated inputs: every file format splitray reads — scene TOML (with its animation
//! tables and OBJ sequences), OBJ, MTL, checkpoints, the EXR parts `splitray merge`
//! reads, and timeline traces — loaded in thousands of deterministic mutations of valid
//! files. Each load gives a scene or an image, or an error that names the file; none
//! panics, aborts, or allocates far more than a file of that size could describe. A
//! scene that loads also passes the loader's own checks at its start, middle and end.
//!
//! The mutations come from a fixed-seed generator, so every failure reproduces; it is
//! reported with its format, seed file, case number, mutations and the mutated input.
//!
//! The loads run in a child process whose address space is capped (`ulimit -v`): an
//! allocation sized by a corrupted count fails there and kills the child, which the
//! parent reports with the case it was loading, instead of the test taking the
//! machine's memory or passing because the allocation was lazily zeroed.
//!
//! Budget: about 9 s for the file in the `ci` profile (nextest, one test at a time, on
//! two busy cores). Every byte offset of each seed is a truncation (the seeds are 0.1 to
//! 2 kB) and each target gets [`CASES`] random cases of one to three edits: 3 000 to
//! 10 000 loads per test at 50 to 300 µs each (a TOML scene loads its meshes too), so
//! that no test takes more than 3 s.

use std::cell::Cell;
use std::fmt;
use std::ops::Range;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

use crate::common::SplitMix64 as Rng;

use sha2::{Digest, Sha256};
use splitray::film::{write_exr, AtomicFile, Film, RenderMetadata};
use splitray::render::checkpoint::SIGNATURE;
use splitray::render::merge::merge_parts;
use splitray::render::{Checkpoint, Fingerprint, PartRecord, PassRanges, Shard};
use splitray::scene::{self, builtin};

/// Random mutations per fuzz target (on top of the truncations at every offset).
const CASES: usize = 1500;

/// The child's address-space cap: loading files of a few kilobytes needs a few tens of
/// megabytes; the rest is the test binary's own mappings and thread stacks.
const ADDRESS_SPACE_KIB: u64 = 1 << 20;

/// Set in the child process the fuzz tests run in, to the test's name.
const CHILD: &str = "SPLITRAY_INPUT_FUZZ_CHILD";

// ---------------------------------------------------------------------------------
// The generator and the mutations.

/// The choices the mutations make.
trait Choose {
    /// Uniform in `0..n` (0 for an empty range).
    fn below(&mut self, n: usize) -> usize;
    fn pick<T: Copy>(&mut self, items: &[T]) -> T;
}

impl Choose for Rng {
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next_u64() % n as u64) as usize
        }
    }

    fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.below(items.len())]
    }
}

/// Numbers that loaders have to refuse or bound: non-finite, out of f32's or an
/// integer's range, negative where a count is meant, empty.
const EXTREME_NUMBERS: &[&str] = &[
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e39",
    "-1e39",
    "-0",
    "0",
    "0.0",
    "4294967296",
    "4294967295",
    "2147483648",
    "-1",
    "18446744073709551616",
    "9223372036854775807",
    "1e999999",
    "-1e-999999",
    "1e-45",
    "65536",
    "16385",
    "0x10",
    "1_0",
    "+1",
    "",
];

/// Tokens inserted into text: the syntax of TOML, OBJ and MTL, out of place.
const TOKENS: &[&str] = &[
    "\n",
    "\r\n",
    " ",
    "[",
    "]",
    "{",
    "}",
    "\"",
    "'",
    "=",
    ",",
    "#",
    "\\",
    "\\\n",
    "/",
    "//",
    "-",
    ".",
    "\0",
    "\u{feff}",
    "é",
    "nan",
    "inf",
    "[[mesh]]\n",
    "[camera]\n",
    "[[camera.keyframe]]\n",
    "[[mesh.keyframe]]\ntime = 0\n",
    "[[material]]\nname = \"x\"\n",
    "[[material.layer]]\n",
    "[[point_light]]\n",
    "[film]\n",
    "[render]\n",
    "sequence = { first = 0, last = 4294967295, fps = 1e-40 }\n",
    "path = \"wave_{:09}.obj\"\n",
    "rotate = { quaternion = [0, 0, 0, 0] }\n",
    "transform = { scale = [0, 1, 1] }\n",
    "\nv 1e38 -1e38 1e38\n",
    "\nv 0 0 0 0\n",
    "\nvt 0.5\n",
    "\nvn 0 0 0\n",
    "\nf 1 2 3\n",
    "\nf -1 -2 -3\n",
    "\nf 1/1/1 2/2/2 3/3/3\n",
    "\nf 4294967296 1 2\n",
    "\nf 1\n",
    "\ng\n",
    "\no\n",
    "\nusemtl\n",
    "\nusemtl nothing\n",
    "\nmtllib\n",
    "\nmtllib missing.mtl other.mtl\n",
    "\nnewmtl\n",
    "\nKd 2 0 0\n",
    "\nKe -1 0 0\n",
    "\nillum 300\n",
    "\nNi 0\n",
    "\nd -5\n",
    "\nTr 7\n",
];

/// Words put in place of a word of a text file.
const WORDS: &[&str] = &[
    "",
    "x",
    "v",
    "vt",
    "vn",
    "f",
    "usemtl",
    "mtllib",
    "newmtl",
    "Kd",
    "Ke",
    "Ns",
    "d",
    "illum",
    "path",
    "time",
    "name",
    "material",
    "bsdf",
    "weight",
    "\"plastic\"",
    "\"\"",
    "\"a.obj\"",
    "\"wave_{}.obj\"",
    "\"..\"",
    "\"/\"",
    "[]",
    "[1]",
    "[1, 2, 3, 4]",
    "{}",
    "true",
    "1/2/3",
    "1//",
    "/1",
    "-0/-0/-0",
    "🙂",
    "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
];

/// Bytes that matter to the text formats' syntax, and a few that do not decode.
const BYTES: &[u8] = b"\0\n\r\t \"'#=[]{},./\\-+e9\xff\xc3";

/// One edit of a file's bytes.
#[derive(Clone, Debug)]
enum Mutation {
    Truncate(usize),
    FlipBit {
        at: usize,
        bit: u8,
    },
    SetByte {
        at: usize,
        byte: u8,
    },
    Insert {
        at: usize,
        bytes: Vec<u8>,
    },
    Delete {
        at: usize,
        len: usize,
    },
    DeleteLine(usize),
    DuplicateLine(usize),
    SwapLines(usize, usize),
    /// The `nth` number of the text (see [`number_spans`]) replaced.
    ReplaceNumber {
        nth: usize,
        with: &'static str,
    },
    /// The `nth` whitespace-separated word replaced.
    ReplaceWord {
        nth: usize,
        with: &'static str,
    },
    /// Bytes overwritten in place: a little-endian count, offset or coordinate.
    SetWord {
        at: usize,
        bytes: Vec<u8>,
    },
    /// A checkpoint's JSON header edited, its length and checksum made right again.
    Resealed(Box<Mutation>),
}

impl fmt::Display for Mutation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = |b: &[u8]| format!("{:?}", String::from_utf8_lossy(b));
        match self {
            Mutation::Truncate(at) => write!(f, "truncate at {at}"),
            Mutation::FlipBit { at, bit } => write!(f, "flip bit {bit} of byte {at}"),
            Mutation::SetByte { at, byte } => write!(f, "set byte {at} to {byte:#04x}"),
            Mutation::Insert { at, bytes } => write!(f, "insert {} at {at}", text(bytes)),
            Mutation::Delete { at, len } => write!(f, "delete {len} bytes at {at}"),
            Mutation::DeleteLine(n) => write!(f, "delete line {n}"),
            Mutation::DuplicateLine(n) => write!(f, "duplicate line {n}"),
            Mutation::SwapLines(a, b) => write!(f, "swap lines {a} and {b}"),
            Mutation::ReplaceNumber { nth, with } => write!(f, "number {nth} := {with:?}"),
            Mutation::ReplaceWord { nth, with } => write!(f, "word {nth} := {with:?}"),
            Mutation::SetWord { at, bytes } => write!(f, "bytes {at}.. := {bytes:02x?}"),
            Mutation::Resealed(m) => write!(f, "in the header, {m}, resealed"),
        }
    }
}

impl Mutation {
    fn apply(&self, input: &[u8]) -> Vec<u8> {
        let clamp = |at: usize| at.min(input.len());
        let splice = |range: Range<usize>, with: &[u8]| {
            let mut out = input[..range.start].to_vec();
            out.extend_from_slice(with);
            out.extend_from_slice(&input[range.end..]);
            out
        };
        let with_byte = |at: usize, f: &dyn Fn(u8) -> u8| {
            let mut out = input.to_vec();
            if let Some(b) = out.get_mut(at) {
                *b = f(*b);
            }
            out
        };
        match self {
            Mutation::Truncate(at) => input[..clamp(*at)].to_vec(),
            Mutation::FlipBit { at, bit } => with_byte(*at, &|b| b ^ (1 << bit)),
            Mutation::SetByte { at, byte } => with_byte(*at, &|_| *byte),
            Mutation::Insert { at, bytes } => splice(clamp(*at)..clamp(*at), bytes),
            Mutation::Delete { at, len } => splice(clamp(*at)..clamp(at + len), b""),
            Mutation::DeleteLine(n) => edit_lines(input, |l| {
                if *n < l.len() {
                    l.remove(*n);
                }
            }),
            Mutation::DuplicateLine(n) => edit_lines(input, |l| {
                if let Some(line) = l.get(*n).cloned() {
                    l.insert(*n, line);
                }
            }),
            Mutation::SwapLines(a, b) => edit_lines(input, |l| {
                if *a < l.len() && *b < l.len() {
                    l.swap(*a, *b);
                }
            }),
            Mutation::ReplaceNumber { nth, with } => match number_spans(input).get(*nth) {
                Some(span) => splice(span.clone(), with.as_bytes()),
                None => input.to_vec(),
            },
            Mutation::ReplaceWord { nth, with } => match word_spans(input).get(*nth) {
                Some(span) => splice(span.clone(), with.as_bytes()),
                None => input.to_vec(),
            },
            Mutation::SetWord { at, bytes } => {
                let mut out = input.to_vec();
                for (k, b) in bytes.iter().enumerate() {
                    if let Some(slot) = out.get_mut(at + k) {
                        *slot = *b;
                    }
                }
                out
            }
            Mutation::Resealed(m) => resealed(input, m),
        }
    }
}

/// `input`'s lines (each with its line break) edited by `edit`, joined again.
fn edit_lines(input: &[u8], edit: impl FnOnce(&mut Vec<Vec<u8>>)) -> Vec<u8> {
    let mut lines: Vec<Vec<u8>> = input
        .split_inclusive(|&b| b == b'\n')
        .map(<[u8]>::to_vec)
        .collect();
    edit(&mut lines);
    lines.concat()
}

fn line_count(input: &[u8]) -> usize {
    input.split_inclusive(|&b| b == b'\n').count()
}

/// The numbers of a text: a digit, with a sign or point before it, and the digits,
/// points, exponents and signs after it.
fn number_spans(input: &[u8]) -> Vec<Range<usize>> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < input.len() {
        if !input[i].is_ascii_digit() {
            i += 1;
            continue;
        }
        let mut start = i;
        while start > 0 && matches!(input[start - 1], b'-' | b'+' | b'.') {
            start -= 1;
        }
        let mut end = i;
        while end < input.len()
            && matches!(input[end], b'0'..=b'9' | b'.' | b'e' | b'E' | b'-' | b'+')
        {
            end += 1;
        }
        spans.push(start..end);
        i = end;
    }
    spans
}

/// The runs of non-whitespace bytes.
fn word_spans(input: &[u8]) -> Vec<Range<usize>> {
    let mut spans = Vec::new();
    let mut start = None;
    for (i, b) in input.iter().enumerate() {
        match (b.is_ascii_whitespace(), start) {
            (false, None) => start = Some(i),
            (true, Some(s)) => {
                spans.push(s..i);
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        spans.push(s..input.len());
    }
    spans
}

/// One random edit of a text file: bytes, lines, numbers or words.
fn text_mutation(rng: &mut Rng, input: &[u8]) -> Mutation {
    let len = input.len();
    let lines = line_count(input);
    match rng.below(13) {
        12 => Mutation::Truncate(rng.below(len)),
        0 => Mutation::FlipBit {
            at: rng.below(len),
            bit: rng.below(8) as u8,
        },
        1 => Mutation::SetByte {
            at: rng.below(len),
            byte: rng.pick(BYTES),
        },
        2 | 3 => Mutation::Insert {
            at: rng.below(len + 1),
            bytes: rng.pick(TOKENS).as_bytes().to_vec(),
        },
        4 => Mutation::Delete {
            at: rng.below(len),
            len: 1 + rng.below(12),
        },
        5 => Mutation::DeleteLine(rng.below(lines)),
        6 => Mutation::DuplicateLine(rng.below(lines)),
        7 => Mutation::SwapLines(rng.below(lines), rng.below(lines)),
        8..=10 => Mutation::ReplaceNumber {
            nth: rng.below(number_spans(input).len()),
            with: rng.pick(EXTREME_NUMBERS),
        },
        _ => Mutation::ReplaceWord {
            nth: rng.below(word_spans(input).len()),
            with: rng.pick(WORDS),
        },
    }
}

/// Little-endian values that corrupt a count, a length, an offset or a coordinate.
fn extreme_word(rng: &mut Rng) -> Vec<u8> {
    const U32: &[u32] = &[
        0,
        1,
        0xffff,
        0x1_0000,
        0x0100_0000,
        0x1000_0000,
        // Within EXR's window limit (2^30 − 1), far beyond any film.
        0x3fff_fff0,
        0x3fff_ffff,
        0x7fff_ffff,
        0x8000_0000,
        0xffff_fffe,
        0xffff_ffff,
    ];
    const U64: &[u64] = &[u64::MAX, 1 << 40, 1 << 62, i64::MIN as u64];
    if rng.below(4) == 0 {
        rng.pick(U64).to_le_bytes().to_vec()
    } else {
        rng.pick(U32).to_le_bytes().to_vec()
    }
}

/// One random edit of a binary file: bits, bytes, or a word (at one of `fields`, the
/// offsets of its counts and sizes, or anywhere).
fn binary_mutation(rng: &mut Rng, input: &[u8], fields: &[usize]) -> Mutation {
    let len = input.len();
    match rng.below(8) {
        7 => Mutation::Truncate(rng.below(len)),
        0 => Mutation::FlipBit {
            at: rng.below(len),
            bit: rng.below(8) as u8,
        },
        1 => Mutation::SetByte {
            at: rng.below(len),
            byte: rng.next_u64() as u8,
        },
        2 => Mutation::Insert {
            at: rng.below(len + 1),
            bytes: (0..1 + rng.below(8))
                .map(|_| rng.next_u64() as u8)
                .collect(),
        },
        3 => Mutation::Delete {
            at: rng.below(len),
            len: 1 + rng.below(8),
        },
        4 | 5 if !fields.is_empty() => Mutation::SetWord {
            at: rng.pick(fields),
            bytes: extreme_word(rng),
        },
        _ => Mutation::SetWord {
            at: rng.below(len),
            bytes: extreme_word(rng),
        },
    }
}

// ---------------------------------------------------------------------------------
// The harness.

/// A file that is mutated and a load that reads it (perhaps through another file).
struct Target<'a> {
    /// The format, for reports.
    format: &'static str,
    /// Where the mutated bytes are written.
    path: PathBuf,
    /// The valid file the mutations start from.
    seed: Vec<u8>,
    /// Loads the file (or the file that refers to it); the error as it is shown.
    load: &'a dyn Fn() -> Result<(), String>,
    /// Whether an error names the file: the tests take its full path, or the name a
    /// referring file gives it. Empty where the caller names the file (the parser has
    /// only its text).
    names: &'a [String],
}

/// A case that went wrong.
struct Failure {
    case: String,
    problem: String,
    input: Vec<u8>,
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut input = String::from_utf8_lossy(&self.input).into_owned();
        if input.len() > 3000 {
            let mut cut = 3000;
            while !input.is_char_boundary(cut) {
                cut -= 1;
            }
            input.truncate(cut);
            input.push_str(" […]");
        }
        write!(
            f,
            "{}\n  {}\n  input ({} bytes):\n{input}",
            self.case,
            self.problem,
            self.input.len()
        )
    }
}

/// The message of the last panic in a load, kept by the hook of [`install_panic_hook`].
static PANIC_MESSAGE: Mutex<Option<String>> = Mutex::new(None);

thread_local! {
    /// Whether this thread is in a load, whose panic is a finding to report rather than
    /// print.
    static LOADING: Cell<bool> = const { Cell::new(false) };
}

/// Keeps a load's panic message for its report; other panics (the test's own
/// assertions) print as usual.
fn install_panic_hook() {
    let usual = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !LOADING.get() {
            return usual(info);
        }
        let payload = info.payload();
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic".to_string());
        let at = info.location().map(|l| l.to_string()).unwrap_or_default();
        *PANIC_MESSAGE.lock().unwrap() = Some(format!("{message} at {at}"));
    }));
}

/// Loads `target` after writing each of `inputs` (a case's description and its bytes)
/// to its file, and returns the failures; restores the seed file at the end.
fn fuzz(target: &Target, inputs: impl IntoIterator<Item = (String, Vec<u8>)>) -> Vec<Failure> {
    let mut failures = Vec::new();
    for (description, input) in inputs {
        let case = format!("{} {}: {description}", target.format, target.path.display());
        std::fs::write(&target.path, &input).unwrap();
        // Said before the load: a child that dies in it leaves this as its last line.
        eprintln!("loading {case}");
        if let Some(problem) = check_load(target) {
            failures.push(Failure {
                case,
                problem,
                input,
            });
        }
    }
    std::fs::write(&target.path, &target.seed).unwrap();
    failures
}

/// What is wrong with loading `target` as its file is now, if anything.
fn check_load(target: &Target) -> Option<String> {
    LOADING.set(true);
    let loaded = catch_unwind(AssertUnwindSafe(target.load));
    LOADING.set(false);
    match loaded {
        Err(_) => {
            let message = PANIC_MESSAGE.lock().unwrap().take();
            Some(format!("panicked: {}", message.unwrap_or_default()))
        }
        Ok(Ok(())) => None,
        Ok(Err(e)) if e.contains("parser panicked") => {
            Some(format!("the OBJ parser panicked: {e}"))
        }
        Ok(Err(e))
            if !target.names.is_empty() && !target.names.iter().any(|n| e.contains(n.as_str())) =>
        {
            Some(format!("the error does not name the file: {e}"))
        }
        Ok(Err(_)) => None,
    }
}

/// The truncations of `seed` at every offset, then `CASES` random cases of one to
/// three mutations from `mutate` seeded with `rng_seed`: each case's description and
/// bytes.
fn cases<'a>(
    seed: &'a [u8],
    rng_seed: u64,
    mutate: &'a dyn Fn(&mut Rng, &[u8]) -> Mutation,
) -> impl Iterator<Item = (String, Vec<u8>)> + 'a {
    let cuts = (0..seed.len()).map(|at| (format!("cut at {at}"), seed[..at].to_vec()));
    let mut rng = Rng(rng_seed);
    let random = (0..CASES).map(move |i| {
        let count = 1 + [0, 0, 0, 1, 2][rng.below(5)];
        let mut bytes = seed.to_vec();
        let mut described = Vec::new();
        for _ in 0..count {
            let m = mutate(&mut rng, &bytes);
            bytes = m.apply(&bytes);
            described.push(m.to_string());
        }
        (
            format!("case {rng_seed:#x}/{i}: {}", described.join("; ")),
            bytes,
        )
    });
    cuts.chain(random)
}

/// Panics with every failure (the first few in full).
fn assert_no_failures(failures: &[Failure]) {
    if failures.is_empty() {
        return;
    }
    let shown: Vec<String> = failures.iter().take(5).map(|f| f.to_string()).collect();
    let cases: Vec<String> = failures
        .iter()
        .map(|f| format!("{}\n  {}", f.case, f.problem))
        .collect();
    panic!(
        "{} mutated inputs went wrong; the first:\n\n{}\n\nall:\n{}",
        failures.len(),
        shown.join("\n\n"),
        cases.join("\n")
    );
}

/// True in the child process that runs `test` alone, under the address-space cap.
/// Otherwise runs it there, fails unless it passed (reporting the case it was loading
/// if it died), and returns false: the caller returns.
fn in_capped_process(test: &str) -> bool {
    if std::env::var_os(CHILD).is_some_and(|name| name == test) {
        install_panic_hook();
        return true;
    }
    let binary = std::env::current_exe().expect("the test binary's path");
    let output = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {ADDRESS_SPACE_KIB} && exec \"$0\" \"$@\""
        ))
        .arg(&binary)
        .args(["--exact", test, "--nocapture", "--test-threads", "1"])
        .env(CHILD, test)
        .output()
        .expect("run the test binary");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    if output.status.success() && stdout.contains("test result: ok. 1 passed") {
        return false;
    }
    // The loads were announced one a line: the last one is the case that failed.
    let last_case = stderr
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("loading "))
        .unwrap_or("(none)");
    let tail: Vec<&str> = stderr
        .lines()
        .filter(|l| !l.starts_with("loading "))
        .collect();
    panic!(
        "{test}, in a process of {} capped at {ADDRESS_SPACE_KIB} KiB: {}\nlast case loaded: \
         {last_case}\n{stdout}\n{}",
        binary.display(),
        output.status,
        tail[tail.len().saturating_sub(60)..].join("\n")
    );
}

// ---------------------------------------------------------------------------------
// Valid seed files.

const FEATURES_OBJ: &str = "\
# Every kind of line the OBJ loader reads.
mtllib features.mtl
o quad
v 0 0 0
v 1 0 0 1
v 1 1 0
v 0 1 0
vt 0 0
vt 1
vt 1 1 0
vn 0 0 1
vn 0 0 1
vn 0 0 1
vn 0 0 1
usemtl red
f 1/1/1 2/2/2 3/3/3 4/1/4
g coloured
v 0 0 1 1 0 0
v 1 0 1 0 1 0
v 0 1 1 0 0 1 # a comment
usemtl lamp
f -3//2 -2//3 \\
  -1//4
usemtl nothing
f 5 6 7
mtllib more.mtl
usemtl more
f 1 3 6
";

const FEATURES_MTL: &str = "\
newmtl red
Ka 0.1 0.1 0.1
Kd 0.6 0.1 0.1
Ks 0.2 0.2 0.2
Ns 20
Ni 1.4
d 1
illum 2

newmtl lamp
Kd 0 0 0
Ke 5 5 5
Tr 0
";

const MORE_MTL: &str = "newmtl more\nKd 0.5 0.5 0.5\n";

/// Three frames of a two-triangle sheet, for a mesh sequence.
fn wave_obj(k: usize) -> String {
    let z = k as f32 * 0.25;
    format!(
        "v 0 0 0\nv 1 0 {z}\nv 1 1 0\nv 0 1 {z}\nvn 0 0 1\nf 1//1 2//1 3//1\nf 1//1 3//1 4//1\n"
    )
}

const ANIMATED_TOML: &str = r#"
name = "everything"

[camera]
look_at = [0.5, 0.5, 0.0]
fov_y = 40

[[camera.keyframe]]
time = 0.0
position = [0.5, 0.5, 3.0]

[[camera.keyframe]]
time = 1.5
position = [1.0, 0.5, 3.0]
up = [0.0, 1.0, 0.1]
fov_y = 30

[film]
width = 64
height = 48

[[mesh]]
path = "features.obj"
transform = { scale = [1.0, 2.0, -1.0], translate = [0.0, 0.0, -1.0], rotate = { quaternion = [0.0, 0.0, 0.38268343, 0.9238795] } }

[[mesh.keyframe]]
time = 0.0
scale = [1.0, 1.0, 1.0]

[[mesh.keyframe]]
time = 1.0
scale = 2
translate = [0.0, 1.0, 0.0]
rotate = { axis = [0.0, 1.0, 0.0], degrees = 90.0 }

[[mesh]]
path = "wave_{:02}.obj"
sequence = { first = 0, last = 2, fps = 24.0 }
material = "glossy"

[[material]]
name = "glossy"
[[material.layer]]
bsdf = "lambert"
reflectance = [0.5, 0.3, 0.1]
weight = 0.7
[[material.layer]]
bsdf = "conductor"
roughness = 0.1
distribution = "beckmann"
weight = 0.3

[[material]]
name = "red"
bsdf = "rough-glass"
roughness = 0.5
ior = 1.5
emission = [0.0, 0.0, 0.0]
diffuse = [0.5, 0.5, 0.5]
specular = [0.1, 0.1, 0.1]
shininess = 10
dissolve = 1
illum = 2

[[point_light]]
position = [0.0, 2.0, 2.0]
intensity = [10.0, 10.0, 10.0]

[render]
spp = 16
seed = 7
integrator = "pt"
tracer = "pdacrt"
max_depth = 5
"#;

/// The repository's scenes and the synthetic files above, in a fresh folder.
fn fixture() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for entry in std::fs::read_dir(&scenes).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, dir.path().join(path.file_name().unwrap())).unwrap();
    }
    let write = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    write("features.obj", FEATURES_OBJ);
    write("features.mtl", FEATURES_MTL);
    write("more.mtl", MORE_MTL);
    write("animated.toml", ANIMATED_TOML);
    for k in 0..3 {
        write(&format!("wave_{k:02}.obj"), &wave_obj(k));
    }
    dir
}

/// Loads the scene file at `path` (`.toml` or `.obj`) as `splitray render` does. A
/// scene that loads must be one a render can use: posed at its start, half way and its
/// end, it passes the checks the loader makes.
fn load_scene(path: &Path) -> Result<(), String> {
    let spec = path.to_str().unwrap();
    let animated = scene::load_animated(spec).map_err(|e| e.to_string())?;
    let end = animated.animation.end_time().unwrap_or(0.0);
    for t in [0.0, 0.5 * end, end] {
        let at = scene::Location::file(format!("{spec} posed at {t} s"));
        if let Err(e) = scene::validate::validate_scene(&animated.pose(t), &at) {
            panic!("loaded a scene that does not validate: {e}");
        }
    }
    Ok(())
}

fn display(path: &Path) -> String {
    path.display().to_string()
}

/// Fuzzes the scene-level file `name` of the fixture (a TOML or an OBJ scene).
fn fuzz_scene_file(name: &str, rng_seed: u64) -> Vec<Failure> {
    let dir = fixture();
    let path = dir.path().join(name);
    assert!(load_scene(&path).is_ok(), "{name} is a valid seed");
    let names = [display(&path)];
    let load = || load_scene(&path);
    let target = Target {
        format: if name.ends_with(".toml") {
            "TOML"
        } else {
            "OBJ"
        },
        seed: std::fs::read(&path).unwrap(),
        path: path.clone(),
        load: &load,
        names: &names,
    };
    fuzz(&target, cases(&target.seed, rng_seed, &text_mutation))
}

// ---------------------------------------------------------------------------------
// Scenes, meshes and material libraries.

#[test]
fn mutated_toml_scenes_load_or_fail_naming_the_file() {
    if !in_capped_process("input_fuzz::mutated_toml_scenes_load_or_fail_naming_the_file") {
        return;
    }
    let mut failures = fuzz_scene_file("animated.toml", 0x7011);
    failures.extend(fuzz_scene_file("cornell-animated.toml", 0x7012));
    failures.extend(fuzz_scene_file("materials.toml", 0x7013));
    assert_no_failures(&failures);
}

#[test]
fn mutated_obj_scenes_load_or_fail_naming_the_file() {
    if !in_capped_process("input_fuzz::mutated_obj_scenes_load_or_fail_naming_the_file") {
        return;
    }
    let mut failures = fuzz_scene_file("features.obj", 0x0B1);
    failures.extend(fuzz_scene_file("cornell-box.obj", 0x0B2));
    assert_no_failures(&failures);
}

/// A material library, or a file of a mesh sequence, mutated under the file that
/// refers to it.
#[test]
fn mutated_material_libraries_and_sequence_files_fail_naming_the_file() {
    if !in_capped_process(
        "input_fuzz::mutated_material_libraries_and_sequence_files_fail_naming_the_file",
    ) {
        return;
    }
    let dir = fixture();
    let mut failures = Vec::new();
    for (referring, name, rng_seed) in [
        ("features.obj", "features.mtl", 0x3711),
        ("cornell-box.obj", "cornell-box.mtl", 0x3712),
        ("animated.toml", "wave_01.obj", 0x3713),
    ] {
        let referring = dir.path().join(referring);
        let path = dir.path().join(name);
        let names = [display(&path), name.to_string()];
        let load = || load_scene(&referring);
        let target = Target {
            format: if name.ends_with(".mtl") {
                "MTL"
            } else {
                "OBJ in a sequence"
            },
            seed: std::fs::read(&path).unwrap(),
            path: path.clone(),
            load: &load,
            names: &names,
        };
        failures.extend(fuzz(&target, cases(&target.seed, rng_seed, &text_mutation)));
    }
    assert_no_failures(&failures);
}

// ---------------------------------------------------------------------------------
// Checkpoints.

/// A checkpoint of a 3×2 film (the format needs no device).
fn small_checkpoint_bytes(dir: &Path) -> Vec<u8> {
    let path = dir.join("seed.ckpt");
    crate::checkpoint::small_checkpoint()
        .write(AtomicFile::create(&path).unwrap())
        .unwrap();
    std::fs::read(&path).unwrap()
}

/// Where a checkpoint's JSON header starts: after the signature, version and length.
const CHECKPOINT_HEADER: usize = SIGNATURE.len() + 8;

/// The offsets of a checkpoint's version and header length.
const CHECKPOINT_FIELDS: [usize; 2] = [SIGNATURE.len(), SIGNATURE.len() + 4];

/// The span of a checkpoint's JSON header, where its length field fits the file.
fn checkpoint_header(bytes: &[u8]) -> Option<Range<usize>> {
    let len = bytes.get(CHECKPOINT_HEADER - 4..CHECKPOINT_HEADER)?;
    let end = CHECKPOINT_HEADER + u32::from_le_bytes(len.try_into().unwrap()) as usize;
    (end + 32 <= bytes.len()).then_some(CHECKPOINT_HEADER..end)
}

/// `bytes` (a checkpoint) with its JSON header edited by `edit`, and the header length
/// and checksum made to match again, so that the edit reaches the reader's checks of
/// the header's values instead of stopping at the checksum.
fn resealed(bytes: &[u8], edit: &Mutation) -> Vec<u8> {
    let Some(header) = checkpoint_header(bytes) else {
        return bytes.to_vec();
    };
    let edited = edit.apply(&bytes[header.clone()]);
    let mut out = bytes[..CHECKPOINT_HEADER - 4].to_vec();
    out.extend_from_slice(&(edited.len() as u32).to_le_bytes());
    out.extend_from_slice(&edited);
    out.extend_from_slice(&bytes[header.end..bytes.len() - 32]);
    let checksum = Sha256::digest(&out);
    out.extend_from_slice(&checksum);
    out
}

/// A binary edit of a checkpoint, or a text edit of its header, resealed.
fn checkpoint_mutation(rng: &mut Rng, bytes: &[u8]) -> Mutation {
    match checkpoint_header(bytes) {
        Some(header) if rng.below(2) == 0 => {
            Mutation::Resealed(Box::new(text_mutation(rng, &bytes[header])))
        }
        _ => binary_mutation(rng, bytes, &CHECKPOINT_FIELDS),
    }
}

#[test]
fn mutated_checkpoints_are_refused_naming_the_file() {
    if !in_capped_process("input_fuzz::mutated_checkpoints_are_refused_naming_the_file") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let seed = small_checkpoint_bytes(dir.path());
    let path = dir.path().join("fuzzed.ckpt");
    let names = [display(&path)];
    let load = || Checkpoint::read(&path).map(drop).map_err(|e| e.to_string());
    let target = Target {
        format: "checkpoint",
        path: path.clone(),
        seed: seed.clone(),
        load: &load,
        names: &names,
    };
    std::fs::write(&path, &seed).unwrap();
    assert_eq!(load(), Ok(()), "the seed checkpoint reads");
    let failures = fuzz(&target, cases(&seed, 0xC4E1, &checkpoint_mutation));
    assert_no_failures(&failures);
}

// ---------------------------------------------------------------------------------
// EXR parts, as `splitray merge` reads them.

/// Shard 0/2 of a 3×2 render with every AOV and its standard error.
fn part_film_and_metadata() -> (Film, RenderMetadata) {
    let scene = builtin("cornell-box").unwrap();
    let rgb: Vec<[f32; 3]> = (0..6).map(|i| [i as f32, 0.5, 1e-3]).collect();
    let mut film = Film::from_mean_rgb(3, 2, &rgb).unwrap();
    film.depth = Some(vec![1.0, 2.0, f32::INFINITY, 0.5, 0.25, 3.0]);
    film.normal = Some(vec![[0.0, 0.0, 1.0]; 6]);
    film.triangle_id = Some(vec![0, 1, 2, u32::MAX, 4, 5]);
    film.stderr = Some(vec![[0.1, 0.2, 0.3]; 6]);
    let record = PartRecord {
        fingerprint: Fingerprint::new(&scene, 3, 2, 7, "pt", 1, Vec::new()),
        passes: PassRanges::single(0..4),
        samples_per_pass: 2,
        second_moments: true,
        shard: Some(Shard::new(0, 2).unwrap()),
    };
    let meta = RenderMetadata {
        spp: 8,
        seed: 7,
        integrator: "pt".into(),
        tracer: "pdacrt".into(),
        device: "test".into(),
        render_time_s: 1.5,
        extra: record.extra(),
    };
    (film, meta)
}

/// Where an EXR's header ends (its offset table starts), by its attributes' sizes.
fn exr_header_end(bytes: &[u8]) -> usize {
    let mut at = 8; // magic number and version
    let text_end = |from: usize| from + bytes[from..].iter().position(|&b| b == 0).unwrap();
    loop {
        let name_end = text_end(at);
        if name_end == at {
            return at + 1;
        }
        let type_end = text_end(name_end + 1);
        let size = u32::from_le_bytes(bytes[type_end + 1..type_end + 5].try_into().unwrap());
        at = type_end + 5 + size as usize;
    }
}

/// The offsets of an EXR's counts, sizes and coordinates: every value of its size,
/// window and channel attributes, each attribute's size, the offset table and the
/// first chunk's header.
fn exr_fields(bytes: &[u8]) -> Vec<usize> {
    let mut fields = Vec::new();
    for name in [
        "dataWindow",
        "displayWindow",
        "channels",
        "compression",
        "lineOrder",
    ] {
        let key = format!("{name}\0");
        let Some(at) = bytes.windows(key.len()).position(|w| w == key.as_bytes()) else {
            continue;
        };
        let type_end = at
            + key.len()
            + bytes[at + key.len()..]
                .iter()
                .position(|&b| b == 0)
                .unwrap();
        fields.extend((0..5).map(|k| type_end + 1 + 4 * k));
    }
    let table = exr_header_end(bytes);
    let first_chunk = u64::from_le_bytes(bytes[table..table + 8].try_into().unwrap()) as usize;
    fields.extend([table, first_chunk, first_chunk + 4]);
    fields
}

/// The EXR of `film` and `meta`, as bytes.
fn exr_bytes(dir: &Path, film: &Film, meta: &RenderMetadata) -> Vec<u8> {
    let path = dir.join("seed.exr");
    write_exr(&path, film, meta).unwrap();
    std::fs::read(&path).unwrap()
}

#[test]
fn mutated_exr_parts_are_refused_naming_the_file() {
    if !in_capped_process("input_fuzz::mutated_exr_parts_are_refused_naming_the_file") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (film, meta) = part_film_and_metadata();
    let seed = exr_bytes(dir.path(), &film, &meta);
    let fields = exr_fields(&seed);
    let path = dir.path().join("fuzzed.exr");
    let names = [display(&path)];
    let load = || merge_parts(&[&path]).map(drop).map_err(|e| e.to_string());
    let target = Target {
        format: "EXR part",
        path: path.clone(),
        seed: seed.clone(),
        load: &load,
        names: &names,
    };
    std::fs::write(&path, &seed).unwrap();
    assert_eq!(load(), Ok(()), "the seed part merges");
    let mutate = |rng: &mut Rng, bytes: &[u8]| binary_mutation(rng, bytes, &fields);
    let mut failures = fuzz(&target, cases(&seed, 0xE1, &mutate));

    // The splitray attributes the merge reads, each with its numbers and words
    // replaced, in files written whole.
    let mut rng = Rng(0xE2);
    let rewritten: Vec<(String, Vec<u8>)> = (0..CASES / 4)
        .map(|i| {
            let mut meta = meta.clone();
            let k = rng.below(meta.extra.len());
            let value = meta.extra[k].1.clone().into_bytes();
            let edit = text_mutation(&mut rng, &value);
            meta.extra[k].1 = String::from_utf8_lossy(&edit.apply(&value)).into_owned();
            let case = format!("metadata {i}: {} {edit}", meta.extra[k].0);
            (case, exr_bytes(dir.path(), &film, &meta))
        })
        .collect();
    failures.extend(fuzz(&target, rewritten));
    assert_no_failures(&failures);
}

// ---------------------------------------------------------------------------------
// Timelines, as `splitray timeline` reads them.

/// A trace with every kind of event the timeline reads: names, sort order, slices with
/// arguments, counters, and metadata.
const TRACE_JSON: &str = r#"{"traceEvents":[
{"ph":"M","name":"process_name","pid":1,"args":{"name":"splitray"}},
{"ph":"M","name":"thread_name","pid":1,"tid":1,"args":{"name":"main"}},
{"ph":"M","name":"thread_sort_index","pid":1,"tid":1,"args":{"sort_index":2}},
{"ph":"X","name":"render","pid":1,"tid":1,"ts":0,"dur":1000,"args":{"rays":5}},
{"ph":"X","name":"trace","pid":1,"tid":1,"ts":100,"dur":500},
{"ph":"C","name":"memory","pid":1,"ts":50,"args":{"bytes":1024}},
{"ph":"C","name":"memory","pid":1,"ts":900,"args":{"bytes":2048}}
],"metadata":{"device":"test"}}"#;

/// The timeline parser has only the text (`splitray timeline` names the file in its
/// errors); a mutated trace parses and draws, or fails, without a panic.
#[test]
fn mutated_timelines_draw_or_fail_without_panicking() {
    if !in_capped_process("input_fuzz::mutated_timelines_draw_or_fail_without_panicking") {
        return;
    }
    use splitray::timeline::{draw, json};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trace.json");
    let load = || {
        let text = std::fs::read(&path).unwrap();
        let trace = json::from_json(&String::from_utf8_lossy(&text)).map_err(|e| e.to_string())?;
        let options = draw::DrawOptions {
            width: 600,
            from_ms: None,
            to_ms: None,
        };
        draw::svg(&trace, &options)
            .map(drop)
            .map_err(|e| e.to_string())
    };
    let target = Target {
        format: "timeline",
        path: path.clone(),
        seed: TRACE_JSON.as_bytes().to_vec(),
        load: &load,
        names: &[],
    };
    std::fs::write(&path, TRACE_JSON).unwrap();
    assert_eq!(load(), Ok(()), "the seed trace draws");
    let failures = fuzz(&target, cases(&target.seed, 0x71, &text_mutation));
    assert_no_failures(&failures);
}

// ---------------------------------------------------------------------------------
// Regressions.

/// A part may be one shard of billions (of a render of as many passes): the shards it
/// leaves missing are named as one run, not listed one by one.
#[test]
fn a_part_of_billions_of_shards_merges_naming_the_missing_ones_as_a_run() {
    if !in_capped_process(
        "input_fuzz::a_part_of_billions_of_shards_merges_naming_the_missing_ones_as_a_run",
    ) {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (film, mut meta) = part_film_and_metadata();
    for (key, value) in &mut meta.extra {
        if key == "shard" {
            *value = "0/4294967295".into();
        }
    }
    let path = dir.path().join("part.exr");
    write_exr(&path, &film, &meta).unwrap();
    let merged = merge_parts(&[&path]).unwrap();
    assert_eq!(
        merged.missing_shards.to_string(),
        "1/4294967295 to 4294967294/4294967295"
    );
}
