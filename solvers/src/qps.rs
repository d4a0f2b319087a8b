//! Writer and reader of QPS files (free MPS with a `QUADOBJ` section, the Maros–Meszaros
//! convention) for [`Qp`].
//!
//! # What the writer writes
//!
//! [`write_qps`] writes, for a QP with `n` variables and `m` rows:
//!
//! * `NAME name`;
//! * `ROWS`: the objective row ` N obj`, then one row `c{i}` per constraint row `i`, typed by
//!   its bounds: `E` if `l_i = u_i` (same bits), `G` if only `l_i` is finite, `L` if only `u_i`
//!   is finite, `G` or `L` with a `RANGES` entry if both are finite and different, and **`N`
//!   if both are infinite** (a free row; see below);
//! * `COLUMNS`: for each column `x{j}`, the objective entry `obj q_j` when `q_j` is not `+0.0`
//!   or when the column has no entry in `A` (so that every column is declared), then every
//!   stored entry of `A` in that column, explicit zeros included (the sparsity pattern is
//!   kept);
//! * `RHS`: one entry `rhs c{i} value` per `E`, `G` and `L` row (`l_i`, or `u_i` for `L`);
//! * `RANGES`: one entry `rng c{i} R` per two-sided row, written as a `G` row with
//!   `rhs = l_i` and `R` the decimal with the fewest significant digits such that the exact
//!   value of `rhs + |R|`, rounded once to the nearest `f64`, is `u_i` (see *Ranges* below);
//!   when `u_i = −0` (which an exact sum `l_i + |R|` cannot give) it is an `L` row with
//!   `rhs = u_i` instead;
//! * `BOUNDS`: ` FR bnd x{j}` for **every** column (the MPS default bound is `x ≥ 0`, and the
//!   variables of a [`Qp`] are free);
//! * `QUADOBJ`: every stored entry of the upper triangle of `P` once, as `x{i} x{j} value`
//!   with `i ≤ j`, grouped by `i` (that is, the lower triangle listed column by column, the
//!   Maros–Meszaros layout); the objective is `½xᵀQx + qᵀx` with `Q` symmetric;
//! * `ENDATA`.
//!
//! Every other number is written with Rust's shortest round-trip formatting (`{:e}`), so
//! `read_qps(write_qps(qp)) == qp` bit for bit, signed zeros and the sparsity pattern
//! (explicit zeros) included. The only exception is the degenerate two-sided row
//! `[+0, −0]` (valid, as `+0 ≤ −0`), which reads back as `[+0, +0]`.
//!
//! **Ranges.** A two-sided row `[l, u]` is stored as a right-hand side and a range, so one
//! bound is recomputed as `rhs ± |R|`. Adding the two parsed `f64`s cannot reproduce every
//! `u`: for `[-0.1, 1/3]` every double sum `-0.1 + R` near `1/3` is a tie that rounds to an
//! even significand, and `1/3` has an odd one. This reader therefore evaluates `rhs ± |R|`
//! **exactly on the decimal fields as written** and rounds once to the nearest `f64` (the
//! value the file denotes, e.g. `rhs 0.1` with range `0.2` gives the `f64` nearest to `0.3`,
//! not `0.1 + 0.2 = 0.30000000000000004`), which lets the writer always find an exact `R`. A
//! reader adding doubles gets the same bound to within about one ulp. Fields that are not
//! plain decimals (`inf`) or sums spanning more than 4000 digits fall back to `f64`
//! arithmetic.
//!
//! # What the reader accepts
//!
//! [`read_qps`] reads free MPS: whitespace-separated fields (names must not contain blanks),
//! section headers starting in the first column, data lines starting with a blank, comment
//! lines starting with `*`, blank lines ignored. Sections: `NAME` (optional; the rest of the
//! line is the name), `OBJSENSE` (`MIN`/`MINIMIZE` only), `ROWS`, `COLUMNS`, `RHS`, `RANGES`,
//! `BOUNDS`, `QUADOBJ` (each off-diagonal entry listed once), `QMATRIX` (the full symmetric
//! matrix, both triangles listed; the reader keeps `(Q + Qᵀ)/2`) and `ENDATA` (required).
//! `ROWS` and `COLUMNS` are required; `ROWS` must precede `COLUMNS`, which must precede the
//! other data sections. Rows and columns may have any names; they are numbered in order of
//! first appearance (rows in `ROWS`, columns in `COLUMNS`). The conventions:
//!
//! * **Rows.** The first `N` row is the objective. **Every further `N` row is kept as a free
//!   constraint row `(-∞, +∞)`** (its `A` entries included, its `RHS`/`RANGES` ignored), so
//!   that the row count of a [`Qp`] round-trips. Other readers usually drop extra `N` rows,
//!   which does not change the feasible set either.
//! * **Right-hand sides** default to `0`. A right-hand side on the objective row (minus the
//!   objective constant) is ignored, as [`Qp`] has no constant term. Only the first `RHS`,
//!   `RANGES` and `BOUNDS` set (by set name) is used; the set name may be omitted.
//! * **Ranges** `R`: on an `L` row `[rhs − |R|, rhs]`, on a `G` row `[rhs, rhs + |R|]`, on an
//!   `E` row `[rhs, rhs + R]` if `R > 0` and `[rhs + R, rhs]` if `R < 0`.
//! * **Variable bounds.** [`Qp`] has no variable bounds, so every column whose bounds are not
//!   `(-∞, +∞)` gets an **extra constraint row** appended after the rows of `ROWS`, in column
//!   order: a single `1` in column `j`, with the bounds `[lo, up]` of the column as `[l, u]`.
//!   A column never mentioned in `BOUNDS` has the MPS default `[0, +∞)` and therefore gets a
//!   row `[0, +∞)`. Bound types: `UP` (if the value is negative and no lower bound was given,
//!   the lower bound becomes `-∞`, the usual convention), `LO`, `FX`, `FR`, `MI` (lower `-∞`),
//!   `PL` (upper `+∞`); integer types (`BV`, `UI`, `LI`, `SC`) are an error. Since the writer
//!   declares every column `FR`, no extra row appears on a round trip.
//! * **Numbers** are parsed by Rust's `f64` parser (`inf`/`-inf` accepted, `NaN` rejected).
//!   Large values such as `1e30` are taken literally, not as infinity. Matrix entries
//!   (`COLUMNS`, `QUADOBJ`) must be finite. Duplicate entries are summed.
//! * Integer `MARKER` lines in `COLUMNS` are an error: the variables of a [`Qp`] are
//!   continuous.
//!
//! The result is checked with [`Qp::validate`] (e.g. contradictory bounds `lo > up`).

use crate::backend::QpError;
use crate::qp::{CscMatrix, Qp};
use std::collections::HashMap;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::Path;
use thiserror::Error;

/// An error while reading a QPS file. Line numbers start at 1.
#[derive(Debug, Error)]
pub enum QpsError {
    /// Reading failed (including invalid UTF-8).
    #[error("I/O error while reading QPS: {0}")]
    Io(#[from] std::io::Error),
    /// A section header that is not a known section.
    #[error("line {line}: unknown section `{token}`")]
    UnknownSection {
        /// Line number.
        line: usize,
        /// The header.
        token: String,
    },
    /// A section that is required is missing (or a section needed before this line is).
    #[error("line {line}: missing section {section}")]
    MissingSection {
        /// Line where the section was needed (one past the last line at end of file).
        line: usize,
        /// Name of the missing section.
        section: &'static str,
    },
    /// A row type other than `N`, `E`, `L`, `G`.
    #[error("line {line}: unknown row type `{token}` (expected N, E, L or G)")]
    UnknownRowType {
        /// Line number.
        line: usize,
        /// The type field.
        token: String,
    },
    /// A row name that was not declared in `ROWS`.
    #[error("line {line}: unknown row `{token}`")]
    UnknownRow {
        /// Line number.
        line: usize,
        /// The row name.
        token: String,
    },
    /// A row name declared twice in `ROWS`.
    #[error("line {line}: row `{token}` is declared twice")]
    DuplicateRow {
        /// Line number.
        line: usize,
        /// The row name.
        token: String,
    },
    /// A column name that was not declared in `COLUMNS`.
    #[error("line {line}: unknown column `{token}`")]
    UnknownColumn {
        /// Line number.
        line: usize,
        /// The column name.
        token: String,
    },
    /// A field that should be a number and is not (or is NaN, or infinite in a matrix entry).
    #[error("line {line}: bad number `{token}`")]
    BadNumber {
        /// Line number.
        line: usize,
        /// The field.
        token: String,
    },
    /// A bound type that does not exist.
    #[error("line {line}: unknown bound type `{token}`")]
    UnknownBoundType {
        /// Line number.
        line: usize,
        /// The type field.
        token: String,
    },
    /// A valid MPS feature that a [`Qp`] cannot represent (integer markers and bounds,
    /// maximisation).
    #[error("line {line}: `{token}` is not supported: {reason}")]
    Unsupported {
        /// Line number.
        line: usize,
        /// The offending field.
        token: String,
        /// Why.
        reason: &'static str,
    },
    /// A line of the wrong shape (number of fields, data outside a section, section order).
    #[error("line {line}: malformed line at `{token}`: {reason}")]
    Malformed {
        /// Line number.
        line: usize,
        /// The first field of the line (or the offending one).
        token: String,
        /// What is wrong.
        reason: &'static str,
    },
    /// The problem read is not a valid [`Qp`] (e.g. a lower bound above an upper bound).
    #[error("the problem read is not a valid QP: {0}")]
    InvalidProblem(#[source] QpError),
}

// ---------------------------------------------------------------------------------------------
// Writer
// ---------------------------------------------------------------------------------------------

/// How one constraint row is written.
enum RowKind {
    /// `N` row (both bounds infinite).
    Free,
    /// `E` row with this right-hand side.
    Eq(f64),
    /// `G` row: right-hand side, and for a two-sided row the `RANGES` field as written.
    Ge(f64, Option<String>),
    /// `L` row: right-hand side, and for a two-sided row the `RANGES` field as written.
    Le(f64, Option<String>),
}

/// The `RANGES` field `R` with the fewest significant digits such that the reader's exact
/// evaluation of `near ± |R|` (see [`offset_bound`]; `+` if `plus`) gives back `far`, if any.
/// The exact decimal difference of the written `far` and `near` qualifies unless `far` is a
/// zero whose sign the exact sum does not give (`−0` as `l + |R|`, `+0` as `u − |R|`).
fn range_field(near: f64, far: f64, plus: bool) -> Option<String> {
    let (ns, fs) = (format!("{near:e}"), format!("{far:e}"));
    let (nd, fd) = (Dec::parse(&ns)?, Dec::parse(&fs)?);
    let d = fd.add(&nd.negated());
    (1..=d.mag.len().max(1))
        .map(|k| d.rounded(k).to_string())
        .find(|r| offset_bound(&ns, r, plus).to_bits() == far.to_bits())
}

/// A two-sided row `l < u`, both finite: `G` with `rhs = l` if exact, else `L` with `rhs = u`.
/// Only the degenerate `[+0, −0]` has neither; it is written as `[+0, +0]`.
fn ranged_row(l: f64, u: f64) -> RowKind {
    if let Some(r) = range_field(l, u, true) {
        RowKind::Ge(l, Some(r))
    } else if let Some(r) = range_field(u, l, false) {
        RowKind::Le(u, Some(r))
    } else {
        RowKind::Ge(l, Some(format!("{:e}", (u - l).abs())))
    }
}

fn row_kind(l: f64, u: f64) -> RowKind {
    match (l.is_finite(), u.is_finite()) {
        (false, false) => RowKind::Free,
        (true, false) => RowKind::Ge(l, None),
        (false, true) => RowKind::Le(u, None),
        (true, true) if l.to_bits() == u.to_bits() => RowKind::Eq(l),
        (true, true) => ranged_row(l, u),
    }
}

/// Upper limit on the digits of an exact decimal sum; beyond it [`offset_bound`] falls back to
/// floating-point arithmetic (the smaller term is then far below an ulp of the larger).
const MAX_EXACT_DIGITS: i64 = 4000;

/// An exact decimal `±mag × 10^exp`, `mag` in decimal digits, most significant first, without
/// leading zeros (empty for zero).
#[derive(Clone, Debug)]
struct Dec {
    neg: bool,
    mag: Vec<u8>,
    exp: i64,
}

impl Dec {
    /// Parses a plain decimal (`[+-]digits[.digits][(e|E)[+-]digits]`); `None` for anything
    /// else (`inf`, `nan`, …) or an absurd exponent.
    fn parse(s: &str) -> Option<Dec> {
        let b = s.as_bytes();
        let mut i = 0;
        let neg = match b.first() {
            Some(b'-') => {
                i = 1;
                true
            }
            Some(b'+') => {
                i = 1;
                false
            }
            _ => false,
        };
        let (mut mag, mut exp, mut any_digit, mut dot) = (Vec::new(), 0i64, false, false);
        while i < b.len() {
            match b[i] {
                c @ b'0'..=b'9' => {
                    any_digit = true;
                    if !(mag.is_empty() && c == b'0') {
                        mag.push(c - b'0');
                    }
                    if dot {
                        exp -= 1;
                    }
                }
                b'.' if !dot => dot = true,
                _ => break,
            }
            i += 1;
        }
        if !any_digit {
            return None;
        }
        if i < b.len() {
            if b[i] != b'e' && b[i] != b'E' {
                return None;
            }
            let e: i64 = s[i + 1..].parse().ok()?;
            if e.unsigned_abs() > 1_000_000 {
                return None;
            }
            exp += e;
        }
        Some(Dec { neg, mag, exp })
    }

    fn negated(&self) -> Dec {
        Dec {
            neg: !self.neg,
            ..self.clone()
        }
    }

    /// The exact sum, with the IEEE sign rules for a zero result (`−0` only for `−0 + −0`).
    fn add(&self, o: &Dec) -> Dec {
        if self.mag.is_empty() && o.mag.is_empty() {
            return Dec {
                neg: self.neg && o.neg,
                mag: Vec::new(),
                exp: 0,
            };
        }
        if self.mag.is_empty() {
            return o.clone();
        }
        if o.mag.is_empty() {
            return self.clone();
        }
        let e = self.exp.min(o.exp);
        let pad = |d: &Dec| {
            let mut v = d.mag.clone();
            v.resize(v.len() + (d.exp - e) as usize, 0);
            v
        };
        let (x, y) = (pad(self), pad(o));
        let (neg, mag) = if self.neg == o.neg {
            (self.neg, add_mag(&x, &y))
        } else {
            match cmp_mag(&x, &y) {
                std::cmp::Ordering::Equal => (false, Vec::new()),
                std::cmp::Ordering::Greater => (self.neg, sub_mag(&x, &y)),
                std::cmp::Ordering::Less => (o.neg, sub_mag(&y, &x)),
            }
        };
        Dec { neg, mag, exp: e }.normalised()
    }

    /// Strips leading zeros (and maps zero to an empty magnitude).
    fn normalised(mut self) -> Dec {
        let z = self.mag.iter().take_while(|&&d| d == 0).count();
        self.mag.drain(..z);
        if self.mag.is_empty() {
            self.exp = 0;
        }
        self
    }

    /// Rounded (half up) to `k ≥ 1` significant digits.
    fn rounded(&self, k: usize) -> Dec {
        if self.mag.len() <= k {
            return self.clone();
        }
        let mut mag = self.mag[..k].to_vec();
        let exp = self.exp + (self.mag.len() - k) as i64;
        if self.mag[k] >= 5 {
            let mut i = k;
            loop {
                if i == 0 {
                    mag.insert(0, 1);
                    break;
                }
                i -= 1;
                if mag[i] == 9 {
                    mag[i] = 0;
                } else {
                    mag[i] += 1;
                    break;
                }
            }
        }
        Dec {
            neg: self.neg,
            mag,
            exp,
        }
    }

    /// The nearest `f64` (Rust's parser rounds arbitrarily long decimals correctly).
    fn to_f64(&self) -> f64 {
        let v: f64 = self
            .to_string()
            .parse()
            .expect("a formatted decimal parses");
        v
    }
}

impl std::fmt::Display for Dec {
    /// `[-]d.ddde±x`, or `0e0` / `-0e0`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.neg {
            f.write_str("-")?;
        }
        if self.mag.is_empty() {
            return f.write_str("0e0");
        }
        write!(f, "{}", self.mag[0])?;
        if self.mag.len() > 1 {
            f.write_str(".")?;
            for d in &self.mag[1..] {
                write!(f, "{d}")?;
            }
        }
        write!(f, "e{}", self.exp + self.mag.len() as i64 - 1)
    }
}

fn cmp_mag(x: &[u8], y: &[u8]) -> std::cmp::Ordering {
    let (zx, zy) = (
        x.iter().take_while(|&&d| d == 0).count(),
        y.iter().take_while(|&&d| d == 0).count(),
    );
    let (x, y) = (&x[zx..], &y[zy..]);
    x.len().cmp(&y.len()).then_with(|| x.cmp(y))
}

/// Sum of two digit strings aligned at their last digit.
fn add_mag(x: &[u8], y: &[u8]) -> Vec<u8> {
    let n = x.len().max(y.len());
    let mut out = vec![0u8; n + 1];
    let mut carry = 0u8;
    for k in 0..n {
        let a = if k < x.len() { x[x.len() - 1 - k] } else { 0 };
        let b = if k < y.len() { y[y.len() - 1 - k] } else { 0 };
        let s = a + b + carry;
        out[n - k] = s % 10;
        carry = s / 10;
    }
    out[0] = carry;
    out
}

/// `x − y` for `x ≥ y`, both aligned at their last digit.
fn sub_mag(x: &[u8], y: &[u8]) -> Vec<u8> {
    let mut out = x.to_vec();
    let mut borrow = 0u8;
    for k in 0..x.len() {
        let i = x.len() - 1 - k;
        let b = if k < y.len() { y[y.len() - 1 - k] } else { 0 } + borrow;
        if out[i] >= b {
            out[i] -= b;
            borrow = 0;
        } else {
            out[i] = out[i] + 10 - b;
            borrow = 1;
        }
    }
    out
}

/// The far bound of a ranged row, `rhs + |R|` (`plus`) or `rhs − |R|`, from the two fields as
/// written: evaluated exactly in decimal and rounded once to the nearest `f64` (the value the
/// file denotes), falling back to `f64` arithmetic for non-decimal fields (`inf`) or sums of
/// more than [`MAX_EXACT_DIGITS`] digits.
fn offset_bound(rhs: &str, range: &str, plus: bool) -> f64 {
    if let (Some(a), Some(mut r)) = (Dec::parse(rhs), Dec::parse(range)) {
        r.neg = !plus;
        let span = a.exp.max(r.exp) - a.exp.min(r.exp);
        if span + (a.mag.len() + r.mag.len()) as i64 <= MAX_EXACT_DIGITS {
            return a.add(&r).to_f64();
        }
    }
    let (a, r): (f64, f64) = (
        rhs.parse().unwrap_or(f64::NAN),
        range.parse().unwrap_or(f64::NAN),
    );
    if plus {
        a + r.abs()
    } else {
        a - r.abs()
    }
}

fn invalid_input(msg: String) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, msg)
}

/// Writes `qp` as a QPS file named `name` (see the [module documentation](self) for the
/// layout). Rows are named `c{i}`, columns `x{j}`, the objective row `obj`.
///
/// Fails with [`std::io::ErrorKind::InvalidInput`] if `qp` does not pass [`Qp::validate`] or if
/// `name` would not read back identically (it contains a line break or leading/trailing
/// blanks). The output is buffered internally and flushed before returning.
pub fn write_qps<W: Write>(qp: &Qp, name: &str, w: W) -> std::io::Result<()> {
    qp.validate()
        .map_err(|e| invalid_input(format!("invalid QP: {e}")))?;
    if name.trim() != name || name.contains(['\n', '\r']) {
        return Err(invalid_input(format!(
            "QPS problem name {name:?} has a line break or leading/trailing blanks"
        )));
    }
    let mut w = BufWriter::new(w);
    let (n, m) = (qp.n(), qp.m());
    let kinds: Vec<RowKind> = (0..m).map(|i| row_kind(qp.l[i], qp.u[i])).collect();

    if name.is_empty() {
        writeln!(w, "NAME")?;
    } else {
        writeln!(w, "NAME {name}")?;
    }

    writeln!(w, "ROWS")?;
    writeln!(w, " N obj")?;
    for (i, k) in kinds.iter().enumerate() {
        let t = match k {
            RowKind::Free => "N",
            RowKind::Eq(_) => "E",
            RowKind::Ge(..) => "G",
            RowKind::Le(..) => "L",
        };
        writeln!(w, " {t} c{i}")?;
    }

    writeln!(w, "COLUMNS")?;
    let a = &qp.a;
    for j in 0..n {
        let (start, end) = (a.colptr[j], a.colptr[j + 1]);
        let q = qp.q[j];
        if q.to_bits() != 0.0f64.to_bits() || start == end {
            writeln!(w, " x{j} obj {q:e}")?;
        }
        for p in start..end {
            writeln!(w, " x{j} c{} {:e}", a.rowval[p], a.nzval[p])?;
        }
    }

    writeln!(w, "RHS")?;
    for (i, k) in kinds.iter().enumerate() {
        match k {
            RowKind::Free => {}
            RowKind::Eq(v) | RowKind::Ge(v, _) | RowKind::Le(v, _) => {
                writeln!(w, " rhs c{i} {v:e}")?;
            }
        }
    }

    writeln!(w, "RANGES")?;
    for (i, k) in kinds.iter().enumerate() {
        if let RowKind::Ge(_, Some(r)) | RowKind::Le(_, Some(r)) = k {
            writeln!(w, " rng c{i} {r}")?;
        }
    }

    writeln!(w, "BOUNDS")?;
    for j in 0..n {
        writeln!(w, " FR bnd x{j}")?;
    }

    writeln!(w, "QUADOBJ")?;
    // The transpose of the upper triangle is the lower triangle in CSC: column i holds the
    // entries (j, i), j ≥ i, of the lower triangle, i.e. the entries (i, j) of P.
    let lower = qp.p.transpose();
    for i in 0..n {
        for p in lower.colptr[i]..lower.colptr[i + 1] {
            writeln!(w, " x{i} x{} {:e}", lower.rowval[p], lower.nzval[p])?;
        }
    }

    writeln!(w, "ENDATA")?;
    w.flush()
}

/// [`write_qps`] to a newly created (or truncated) file.
pub fn write_qps_file(qp: &Qp, name: &str, path: &Path) -> std::io::Result<()> {
    let f = std::fs::File::create(path)?;
    write_qps(qp, name, f)
}

// ---------------------------------------------------------------------------------------------
// Reader
// ---------------------------------------------------------------------------------------------

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Section {
    Name,
    ObjSense,
    Rows,
    Columns,
    Rhs,
    Ranges,
    Bounds,
    QuadObj,
    QMatrix,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum RowType {
    E,
    L,
    G,
    /// A non-objective `N` row: free.
    N,
}

/// Bounds of one column while reading `BOUNDS`.
#[derive(Clone, Copy)]
struct ColBounds {
    lo: f64,
    up: f64,
    lo_set: bool,
}

/// The state of the reader.
#[derive(Default)]
struct Reader {
    name: String,
    seen: Vec<Section>,
    section: Option<Section>,
    /// Name of the objective row, once seen.
    obj: Option<String>,
    /// Constraint rows: name → index.
    row_index: HashMap<String, usize>,
    row_type: Vec<RowType>,
    /// Right-hand side of each constraint row: value and field as written.
    rhs: Vec<(f64, String)>,
    /// Range of each constraint row: value and field as written.
    range: Vec<Option<(f64, String)>>,
    col_index: HashMap<String, usize>,
    /// Objective coefficients (`None` until a first entry, so that `-0.0` survives).
    q: Vec<Option<f64>>,
    a: Vec<(usize, usize, f64)>,
    p: Vec<(usize, usize, f64)>,
    bounds: Vec<ColBounds>,
    rhs_set: Option<String>,
    ranges_set: Option<String>,
    bounds_set: Option<String>,
}

fn parse_num(line: usize, tok: &str) -> Result<f64, QpsError> {
    match tok.parse::<f64>() {
        Ok(v) if !v.is_nan() => Ok(v),
        _ => Err(QpsError::BadNumber {
            line,
            token: tok.to_string(),
        }),
    }
}

fn parse_finite(line: usize, tok: &str) -> Result<f64, QpsError> {
    let v = parse_num(line, tok)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(QpsError::BadNumber {
            line,
            token: tok.to_string(),
        })
    }
}

fn malformed(line: usize, tok: &str, reason: &'static str) -> QpsError {
    QpsError::Malformed {
        line,
        token: tok.to_string(),
        reason,
    }
}

/// Whether this line belongs to the first set of its section (recording the set name).
fn in_first_set(set: &mut Option<String>, name: &str) -> bool {
    match set {
        None => {
            *set = Some(name.to_string());
            true
        }
        Some(s) => s == name,
    }
}

impl Reader {
    /// What a row name refers to: `Ok(None)` for the objective row.
    fn row(&self, line: usize, tok: &str) -> Result<Option<usize>, QpsError> {
        if self.obj.as_deref() == Some(tok) {
            return Ok(None);
        }
        match self.row_index.get(tok) {
            Some(&i) => Ok(Some(i)),
            None => Err(QpsError::UnknownRow {
                line,
                token: tok.to_string(),
            }),
        }
    }

    fn col(&self, line: usize, tok: &str) -> Result<usize, QpsError> {
        self.col_index
            .get(tok)
            .copied()
            .ok_or_else(|| QpsError::UnknownColumn {
                line,
                token: tok.to_string(),
            })
    }

    fn header(&mut self, line: usize, text: &str) -> Result<bool, QpsError> {
        let mut toks = text.split_whitespace();
        let head = toks.next().unwrap_or_default();
        let sec = match head {
            "NAME" => Section::Name,
            "OBJSENSE" => Section::ObjSense,
            "ROWS" => Section::Rows,
            "COLUMNS" => Section::Columns,
            "RHS" => Section::Rhs,
            "RANGES" => Section::Ranges,
            "BOUNDS" => Section::Bounds,
            "QUADOBJ" => Section::QuadObj,
            "QMATRIX" => Section::QMatrix,
            "ENDATA" => {
                self.require(line, Section::Columns, "COLUMNS")?;
                return Ok(true);
            }
            _ => {
                return Err(QpsError::UnknownSection {
                    line,
                    token: head.to_string(),
                })
            }
        };
        if self.seen.contains(&sec) {
            return Err(malformed(line, head, "section appears twice"));
        }
        match sec {
            Section::Name | Section::ObjSense => {
                if self.seen.contains(&Section::Rows) {
                    return Err(malformed(line, head, "section must come before ROWS"));
                }
            }
            Section::Rows => {}
            Section::Columns => self.require(line, Section::Rows, "ROWS")?,
            _ => self.require(line, Section::Columns, "COLUMNS")?,
        }
        if matches!(sec, Section::QuadObj | Section::QMatrix)
            && (self.seen.contains(&Section::QuadObj) || self.seen.contains(&Section::QMatrix))
        {
            return Err(malformed(line, head, "both QUADOBJ and QMATRIX given"));
        }
        self.seen.push(sec);
        self.section = Some(sec);
        match sec {
            Section::Name => {
                self.name = text[head.len()..].trim().to_string();
            }
            Section::ObjSense => {
                if let Some(t) = toks.next() {
                    self.objsense(line, t)?;
                }
            }
            _ => {}
        }
        Ok(false)
    }

    fn require(&self, line: usize, sec: Section, name: &'static str) -> Result<(), QpsError> {
        if self.seen.contains(&sec) {
            Ok(())
        } else {
            Err(QpsError::MissingSection {
                line,
                section: name,
            })
        }
    }

    fn objsense(&self, line: usize, t: &str) -> Result<(), QpsError> {
        match t {
            "MIN" | "MINIMIZE" => Ok(()),
            "MAX" | "MAXIMIZE" => Err(QpsError::Unsupported {
                line,
                token: t.to_string(),
                reason: "only minimisation problems are read",
            }),
            _ => Err(malformed(line, t, "expected MIN or MAX")),
        }
    }

    fn data(&mut self, line: usize, toks: &[&str]) -> Result<(), QpsError> {
        let Some(sec) = self.section else {
            return Err(malformed(line, toks[0], "data line before any section"));
        };
        match sec {
            Section::Name => Err(malformed(line, toks[0], "data line in NAME")),
            Section::ObjSense => {
                if toks.len() != 1 {
                    return Err(malformed(line, toks[0], "expected MIN or MAX"));
                }
                self.objsense(line, toks[0])
            }
            Section::Rows => self.rows_line(line, toks),
            Section::Columns => self.columns_line(line, toks),
            Section::Rhs => self.rhs_line(line, toks),
            Section::Ranges => self.ranges_line(line, toks),
            Section::Bounds => self.bounds_line(line, toks),
            Section::QuadObj | Section::QMatrix => self.quad_line(line, toks, sec),
        }
    }

    fn rows_line(&mut self, line: usize, toks: &[&str]) -> Result<(), QpsError> {
        if toks.len() != 2 {
            return Err(malformed(
                line,
                toks[0],
                "expected a row type and a row name",
            ));
        }
        let (t, name) = (toks[0], toks[1]);
        let ty = match t {
            "N" if self.obj.is_none() => {
                if self.row_index.contains_key(name) {
                    return Err(QpsError::DuplicateRow {
                        line,
                        token: name.to_string(),
                    });
                }
                self.obj = Some(name.to_string());
                return Ok(());
            }
            "N" => RowType::N,
            "E" => RowType::E,
            "L" => RowType::L,
            "G" => RowType::G,
            _ => {
                return Err(QpsError::UnknownRowType {
                    line,
                    token: t.to_string(),
                })
            }
        };
        if self.row_index.contains_key(name) || self.obj.as_deref() == Some(name) {
            return Err(QpsError::DuplicateRow {
                line,
                token: name.to_string(),
            });
        }
        self.row_index.insert(name.to_string(), self.row_type.len());
        self.row_type.push(ty);
        self.rhs.push((0.0, "0".to_string()));
        self.range.push(None);
        Ok(())
    }

    fn columns_line(&mut self, line: usize, toks: &[&str]) -> Result<(), QpsError> {
        if let Some(t) = toks.iter().find(|t| t.trim_matches('\'') == "MARKER") {
            return Err(QpsError::Unsupported {
                line,
                token: t.to_string(),
                reason: "integer MARKER lines are not supported (QP variables are continuous)",
            });
        }
        if toks.len() != 3 && toks.len() != 5 {
            return Err(malformed(
                line,
                toks[0],
                "expected a column name and one or two (row, value) pairs",
            ));
        }
        let name = toks[0];
        let j = match self.col_index.get(name) {
            Some(&j) => j,
            None => {
                let j = self.q.len();
                self.col_index.insert(name.to_string(), j);
                self.q.push(None);
                j
            }
        };
        for pair in toks[1..].chunks(2) {
            let row = self.row(line, pair[0])?;
            let v = parse_finite(line, pair[1])?;
            match row {
                None => {
                    let q = &mut self.q[j];
                    *q = Some(q.map_or(v, |old| old + v));
                }
                Some(i) => self.a.push((i, j, v)),
            }
        }
        Ok(())
    }

    /// Splits an `RHS`/`RANGES` line into its set name (possibly omitted) and its pairs.
    fn set_and_pairs<'a>(
        line: usize,
        toks: &'a [&'a str],
    ) -> Result<(&'a str, &'a [&'a str]), QpsError> {
        match toks.len() {
            2 | 4 => Ok(("", toks)),
            3 | 5 => Ok((toks[0], &toks[1..])),
            _ => Err(malformed(
                line,
                toks[0],
                "expected an optional set name and one or two (row, value) pairs",
            )),
        }
    }

    fn rhs_line(&mut self, line: usize, toks: &[&str]) -> Result<(), QpsError> {
        let (set, pairs) = Self::set_and_pairs(line, toks)?;
        if !in_first_set(&mut self.rhs_set, set) {
            return Ok(());
        }
        for pair in pairs.chunks(2) {
            let row = self.row(line, pair[0])?;
            let v = parse_num(line, pair[1])?;
            // On the objective row: minus the objective constant, which a Qp does not hold.
            if let Some(i) = row {
                self.rhs[i] = (v, pair[1].to_string());
            }
        }
        Ok(())
    }

    fn ranges_line(&mut self, line: usize, toks: &[&str]) -> Result<(), QpsError> {
        let (set, pairs) = Self::set_and_pairs(line, toks)?;
        if !in_first_set(&mut self.ranges_set, set) {
            return Ok(());
        }
        for pair in pairs.chunks(2) {
            let row = self.row(line, pair[0])?;
            let v = parse_num(line, pair[1])?;
            if let Some(i) = row {
                self.range[i] = Some((v, pair[1].to_string()));
            }
        }
        Ok(())
    }

    fn bounds_line(&mut self, line: usize, toks: &[&str]) -> Result<(), QpsError> {
        let ty = toks[0];
        let needs_value = match ty {
            "UP" | "LO" | "FX" => true,
            "FR" | "MI" | "PL" => false,
            "BV" | "UI" | "LI" | "SC" => {
                return Err(QpsError::Unsupported {
                    line,
                    token: ty.to_string(),
                    reason: "integer and semi-continuous bounds are not supported",
                })
            }
            _ => {
                return Err(QpsError::UnknownBoundType {
                    line,
                    token: ty.to_string(),
                })
            }
        };
        // Fields after the type: [set] column [value].
        let rest = &toks[1..];
        let (set, col, value) = match (needs_value, rest.len()) {
            (true, 2) => ("", rest[0], Some(rest[1])),
            (true, 3) => (rest[0], rest[1], Some(rest[2])),
            (false, 1) => ("", rest[0], None),
            // A value after FR/MI/PL is tolerated and ignored: `set column` or `column value`.
            (false, 2) if self.col_index.contains_key(rest[1]) => (rest[0], rest[1], None),
            (false, 2) => ("", rest[0], None),
            (false, 3) => (rest[0], rest[1], None),
            _ => {
                return Err(malformed(
                    line,
                    ty,
                    "expected a bound type, an optional set name, a column and a value",
                ))
            }
        };
        if !in_first_set(&mut self.bounds_set, set) {
            return Ok(());
        }
        let j = self.col(line, col)?;
        let v = value.map(|t| parse_num(line, t)).transpose()?;
        let b = &mut self.bounds_mut()[j];
        match (ty, v) {
            ("UP", Some(v)) => {
                b.up = v;
                if v < 0.0 && !b.lo_set {
                    b.lo = f64::NEG_INFINITY;
                }
            }
            ("LO", Some(v)) => {
                b.lo = v;
                b.lo_set = true;
            }
            ("FX", Some(v)) => {
                b.lo = v;
                b.up = v;
                b.lo_set = true;
            }
            ("FR", _) => {
                b.lo = f64::NEG_INFINITY;
                b.up = f64::INFINITY;
                b.lo_set = true;
            }
            ("MI", _) => {
                b.lo = f64::NEG_INFINITY;
                b.lo_set = true;
            }
            ("PL", _) => b.up = f64::INFINITY,
            _ => unreachable!("bound type checked above"),
        }
        Ok(())
    }

    fn quad_line(&mut self, line: usize, toks: &[&str], sec: Section) -> Result<(), QpsError> {
        if toks.len() != 3 {
            return Err(malformed(
                line,
                toks[0],
                "expected two column names and a value",
            ));
        }
        let a = self.col(line, toks[0])?;
        let b = self.col(line, toks[1])?;
        let mut v = parse_finite(line, toks[2])?;
        if sec == Section::QMatrix && a != b {
            v *= 0.5;
        }
        self.p.push((a.min(b), a.max(b), v));
        Ok(())
    }

    /// The bounds of the columns, sized to the columns read (all defaulting to `[0, +∞)`).
    fn bounds_mut(&mut self) -> &mut [ColBounds] {
        self.bounds.resize(
            self.q.len(),
            ColBounds {
                lo: 0.0,
                up: f64::INFINITY,
                lo_set: false,
            },
        );
        &mut self.bounds
    }

    fn finish(mut self) -> Result<(String, Qp), QpsError> {
        self.bounds_mut();
        let n = self.q.len();
        let q: Vec<f64> = self.q.iter().map(|v| v.unwrap_or(0.0)).collect();
        let mut l = Vec::with_capacity(self.row_type.len());
        let mut u = Vec::with_capacity(self.row_type.len());
        for i in 0..self.row_type.len() {
            let (rhs, ref rhs_tok) = self.rhs[i];
            let far = |plus: bool, r: &str| offset_bound(rhs_tok, r, plus);
            let (li, ui) = match (self.row_type[i], &self.range[i]) {
                (RowType::N, _) => (f64::NEG_INFINITY, f64::INFINITY),
                (RowType::E, Some((r, t))) if *r > 0.0 => (rhs, far(true, t)),
                (RowType::E, Some((r, t))) if *r < 0.0 => (far(false, t), rhs),
                (RowType::E, _) => (rhs, rhs),
                (RowType::L, None) => (f64::NEG_INFINITY, rhs),
                (RowType::L, Some((_, t))) => (far(false, t), rhs),
                (RowType::G, None) => (rhs, f64::INFINITY),
                (RowType::G, Some((_, t))) => (rhs, far(true, t)),
            };
            l.push(li);
            u.push(ui);
        }
        let mut a = self.a;
        for (j, b) in self.bounds.iter().enumerate() {
            if b.lo != f64::NEG_INFINITY || b.up != f64::INFINITY {
                a.push((l.len(), j, 1.0));
                l.push(b.lo);
                u.push(b.up);
            }
        }
        let m = l.len();
        let a = CscMatrix::from_triplets(m, n, &a).map_err(QpsError::InvalidProblem)?;
        let p = CscMatrix::from_triplets(n, n, &self.p).map_err(QpsError::InvalidProblem)?;
        let qp = Qp { p, q, a, l, u };
        qp.validate().map_err(QpsError::InvalidProblem)?;
        Ok((self.name, qp))
    }
}

/// Reads a QPS file (see the [module documentation](self) for what is accepted and how
/// variable bounds and extra `N` rows are mapped onto a [`Qp`]). Returns the problem name
/// (empty if there is no `NAME` line) and the QP.
pub fn read_qps<R: BufRead>(r: R) -> Result<(String, Qp), QpsError> {
    let mut rd = Reader::default();
    let mut last = 0;
    for (k, text) in r.lines().enumerate() {
        let text = text?;
        let line = k + 1;
        last = line;
        let trimmed = text.trim();
        if trimmed.is_empty() || trimmed.starts_with('*') {
            continue;
        }
        if !text.starts_with(char::is_whitespace) {
            if rd.header(line, &text)? {
                return rd.finish();
            }
            continue;
        }
        let toks: Vec<&str> = trimmed.split_whitespace().collect();
        rd.data(line, &toks)?;
    }
    Err(QpsError::MissingSection {
        line: last + 1,
        section: "ENDATA",
    })
}

/// [`read_qps`] from a file.
pub fn read_qps_file(path: &Path) -> Result<(String, Qp), QpsError> {
    let f = std::fs::File::open(path)?;
    read_qps(BufReader::new(f))
}
