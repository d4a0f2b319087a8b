//! QPS writer and reader: exact round trips (hand-made and random QPs with awkward floats),
//! reading a hand-written Maros–Meszaros-style file (names, default and explicit variable
//! bounds, ranges on every row type), and errors naming the line and the offending token.

use contactlab_solvers::qps::*;
use contactlab_solvers::{CscMatrix, Qp};

const INF: f64 = f64::INFINITY;

fn write_string(qp: &Qp, name: &str) -> String {
    let mut buf = Vec::new();
    write_qps(qp, name, &mut buf).unwrap();
    String::from_utf8(buf).unwrap()
}

fn read_str(text: &str) -> Result<(String, Qp), QpsError> {
    read_qps(text.as_bytes())
}

/// Every field of a QP, floats as bits (so that `-0.0 ≠ 0.0` and NaN would be caught).
type Bits = (
    Vec<usize>,
    Vec<usize>,
    Vec<u64>,
    Vec<u64>,
    Vec<usize>,
    Vec<usize>,
    Vec<u64>,
    Vec<u64>,
    Vec<u64>,
    [usize; 4],
);

fn bits(qp: &Qp) -> Bits {
    let b = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    (
        qp.p.colptr.clone(),
        qp.p.rowval.clone(),
        b(&qp.p.nzval),
        b(&qp.q),
        qp.a.colptr.clone(),
        qp.a.rowval.clone(),
        b(&qp.a.nzval),
        b(&qp.l),
        b(&qp.u),
        [qp.p.nrows, qp.p.ncols, qp.a.nrows, qp.a.ncols],
    )
}

fn round_trip(qp: &Qp, name: &str) -> (String, Qp) {
    let text = write_string(qp, name);
    read_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Rows: 0 equality, 1 lower only, 2 upper only, 3 ranged, 4 free, 5 ranged around zero.
/// Column 3 has no entry in A and q_3 = 0; q_1 = 0 too; P has off-diagonal entries.
fn hand_made() -> Qp {
    let p = CscMatrix::from_triplets(
        4,
        4,
        &[
            (0, 0, 2.0),
            (0, 1, -0.5),
            (1, 1, 1.0),
            (1, 3, 0.25),
            (2, 2, 3.0),
            (3, 3, 1e-3),
        ],
    )
    .unwrap();
    let a = CscMatrix::from_triplets(
        6,
        4,
        &[
            (0, 0, 1.0),
            (0, 1, 1.0),
            (1, 0, -1.0),
            (1, 2, 2.0),
            (2, 1, 0.5),
            (3, 2, 1.0),
            (3, 0, 4.0),
            (4, 1, 1.0),
            (4, 2, 0.0), // explicit zero: the pattern must survive
            (5, 0, 1.0),
        ],
    )
    .unwrap();
    Qp {
        p,
        q: vec![1.5, 0.0, -2.0, 0.0],
        a,
        l: vec![1.0, -3.0, -INF, 0.5, -INF, -0.25],
        u: vec![1.0, INF, 7.0, 2.75, INF, 0.125],
    }
}

#[test]
fn hand_made_round_trip_is_exact() {
    let qp = hand_made();
    let text = write_string(&qp, "HANDMADE");
    for needle in [
        "NAME HANDMADE",
        " N obj",
        " E c0",
        " G c1",
        " L c2",
        " N c4",
        " x3 obj 0e0",
        " FR bnd x3",
        " x1 x3 2.5e-1",
        "QUADOBJ",
        "ENDATA",
    ] {
        assert!(text.contains(needle), "missing {needle:?} in\n{text}");
    }
    assert!(
        !text.contains(" x1 obj"),
        "q_1 = 0 with A entries is not written\n{text}"
    );
    let (name, back) = read_str(&text).unwrap();
    assert_eq!(name, "HANDMADE");
    assert_eq!(back, qp);
    assert_eq!(bits(&back), bits(&qp));
}

#[test]
fn empty_name_and_empty_problem_round_trip() {
    let qp = Qp {
        p: CscMatrix::zeros(0, 0),
        q: vec![],
        a: CscMatrix::zeros(0, 0),
        l: vec![],
        u: vec![],
    };
    let (name, back) = round_trip(&qp, "");
    assert_eq!(name, "");
    assert_eq!(back, qp);
}

#[test]
fn file_round_trip() {
    let qp = hand_made();
    let path = std::env::temp_dir().join(format!("contactlab-qps-{}.qps", std::process::id()));
    write_qps_file(&qp, "FILE", &path).unwrap();
    let (name, back) = read_qps_file(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(name, "FILE");
    assert_eq!(bits(&back), bits(&qp));
}

/// A 64-bit LCG (Knuth's MMIX constants); the high bits are used.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0 >> 11
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn unit(&mut self) -> f64 {
        (self.next() as f64) / ((1u64 << 53) as f64)
    }
    /// An awkward float: tiny, huge, subnormal, signed zero, non-terminating binary
    /// fractions, or a random one over many binades.
    fn awkward(&mut self) -> f64 {
        const SET: [f64; 12] = [
            1e-300,
            -0.1,
            1.0 / 3.0,
            1e300,
            -1e300,
            -0.0,
            0.0,
            5e-324,
            -2.0 / 3.0,
            0.1 + 0.2,
            1e-7,
            -123456.789,
        ];
        if self.below(3) == 0 {
            let mant = 2.0 * self.unit() - 1.0;
            mant * 10f64.powi(self.below(41) as i32 - 20)
        } else {
            SET[self.below(SET.len())]
        }
    }
    fn positive(&mut self) -> f64 {
        loop {
            let v = self.awkward().abs();
            if v > 0.0 {
                return v;
            }
        }
    }
}

fn random_qp(rng: &mut Lcg) -> Qp {
    let n = 1 + rng.below(7);
    let m = rng.below(9);
    let mut pt = Vec::new();
    for j in 0..n {
        for i in 0..=j {
            if rng.below(3) == 0 {
                pt.push((i, j, rng.awkward()));
            }
        }
    }
    let mut at = Vec::new();
    for i in 0..m {
        for j in 0..n {
            if rng.below(3) == 0 {
                at.push((i, j, rng.awkward()));
            }
        }
    }
    let q = (0..n)
        .map(|_| {
            if rng.below(3) == 0 {
                0.0
            } else {
                rng.awkward()
            }
        })
        .collect();
    let mut l = Vec::new();
    let mut u = Vec::new();
    for _ in 0..m {
        let v = rng.awkward();
        let (li, ui) = match rng.below(5) {
            0 => (v, v),
            1 => (v, INF),
            2 => (-INF, v),
            3 => (-INF, INF),
            // Two-sided: two independent values (equal ones make an equality row) or v and a
            // near neighbour.
            _ => {
                let w = if rng.below(2) == 0 {
                    rng.awkward()
                } else {
                    v + rng.positive() * 1e-15 * v.abs()
                };
                if v < w {
                    (v, w)
                } else if w < v {
                    (w, v)
                } else {
                    (v, v)
                }
            }
        };
        l.push(li);
        u.push(ui);
    }
    let qp = Qp {
        p: CscMatrix::from_triplets(n, n, &pt).unwrap(),
        q,
        a: CscMatrix::from_triplets(m, n, &at).unwrap(),
        l,
        u,
    };
    qp.validate().unwrap();
    qp
}

#[test]
fn random_round_trips_are_bit_exact() {
    let mut rng = Lcg(0x5eed_1234_abcd_0001);
    for k in 0..500 {
        let qp = random_qp(&mut rng);
        let name = format!("RAND{k}");
        let (back_name, back) = round_trip(&qp, &name);
        assert_eq!(back_name, name);
        assert_eq!(
            bits(&back),
            bits(&qp),
            "QP {k}:\n{}",
            write_string(&qp, &name)
        );
    }
}

#[test]
fn ranges_between_awkward_values_are_exact() {
    let vals: [f64; 11] = [
        1e-300,
        -0.1,
        1.0 / 3.0,
        1e300,
        -1e300,
        -0.0,
        0.0,
        5e-324,
        -1e-300,
        0.1,
        -1.0 / 3.0,
    ];
    let a = CscMatrix::from_triplets(1, 1, &[(0, 0, 1.0)]).unwrap();
    for &x in &vals {
        for &y in &vals {
            // x < y, or the signed-zero pair [-0, +0].
            if x < y || (x == y && x.is_sign_negative() && y.is_sign_positive()) {
                let (l, u) = (x, y);
                let qp = Qp {
                    p: CscMatrix::zeros(1, 1),
                    q: vec![1.0],
                    a: a.clone(),
                    l: vec![l],
                    u: vec![u],
                };
                let (_, back) = round_trip(&qp, "R");
                assert_eq!(bits(&back), bits(&qp), "[{l:e}, {u:e}]");
            }
        }
    }
}

/// Two-sided rows that no pair of doubles `(rhs, R)` reproduces with `f64` addition (every
/// sum is a tie, or the far bound lies between two sums) are exact thanks to the decimal
/// evaluation of `rhs + |R|`.
#[test]
fn ranges_are_exact_where_double_addition_is_not() {
    let eps = f64::EPSILON;
    for (l, u) in [
        (-0.1, 1.0 / 3.0),
        (-1.0, 1.0 + eps),
        (0.1, 0.4),
        (-1e300, 1e-300),
        (-5e-324, 1e300),
        (f64::MIN, f64::MAX),
        (-0.0, 0.0),
        (1.0, 1.0 + eps),
    ] {
        let qp = Qp {
            p: CscMatrix::zeros(1, 1),
            q: vec![0.0],
            a: CscMatrix::from_triplets(1, 1, &[(0, 0, 1.0)]).unwrap(),
            l: vec![l],
            u: vec![u],
        };
        let (_, back) = round_trip(&qp, "EXACT");
        assert_eq!(bits(&back), bits(&qp), "[{l:e}, {u:e}]");
    }
}

/// The degenerate row `[+0, −0]` (valid: `+0 ≤ −0`) is the one documented inexact case.
#[test]
fn degenerate_signed_zero_row_reads_as_plus_zero() {
    let qp = Qp {
        p: CscMatrix::zeros(1, 1),
        q: vec![0.0],
        a: CscMatrix::from_triplets(1, 1, &[(0, 0, 1.0)]).unwrap(),
        l: vec![0.0],
        u: vec![-0.0],
    };
    let (_, back) = round_trip(&qp, "ZERO");
    assert_eq!((back.l[0].to_bits(), back.u[0].to_bits()), (0, 0));
}

/// The reader gives the `f64` nearest to the exact decimal `rhs ± |R|`.
#[test]
fn ranges_are_evaluated_exactly_in_decimal() {
    let text = "\
ROWS
 N obj
 G g
 L l
 E e
COLUMNS
 x g 1 l 1
 x e 1
RHS
 rhs g 0.1 l 0.3
 rhs e 1e300
RANGES
 rng g 0.2 l -0.2
 rng e -1e-300
BOUNDS
 FR bnd x
ENDATA
";
    let (_, qp) = read_str(text).unwrap();
    assert_eq!(qp.u[0].to_bits(), 0.3f64.to_bits());
    assert_ne!(qp.u[0], 0.1 + 0.2);
    assert_eq!(qp.l[1].to_bits(), 0.1f64.to_bits());
    assert_eq!((qp.l[2], qp.u[2]), (1e300, 1e300));
}

const MM_TEXT: &str = "\
* A small QP in the Maros-Meszaros layout.
NAME          QPEX
ROWS
 N  COST
 L  R1
 G  R2
 E  R3
 E  R4
 N  FREE
 E  R5
COLUMNS
    C1        COST      1.0        R1        1.0
    C1        R2        2.0
    C2        COST      -2.0       R1        1.0
    C2        R3        1.0        R4        1.0
    C3        R5        1.0        FREE      3.0
    C4        R2        -1.0
RHS
    RHS       COST      -4.5
    RHS       R1        10.0       R2        1.0
    RHS       R3        2.0        R4        3.0
    RHS       R5        -1.0
RANGES
    RNG       R1        4.0
    RNG       R3        1.5        R4        -1.5
    RNG       R2        -2.0
BOUNDS
 UP BND       C1        4.0
 FR BND       C2
 UP BND       C4        -1.0
QUADOBJ
    C1        C1        2.0
    C1        C2        -1.0
    C2        C2        4.0
    C4        C3        0.5
ENDATA
";

#[test]
fn reads_maros_meszaros_style_text() {
    let (name, qp) = read_str(MM_TEXT).unwrap();
    assert_eq!(name, "QPEX");
    // Columns C1..C4 → 0..3; rows R1, R2, R3, R4, FREE, R5 → 0..5, then the bound rows of
    // C1 ([0, 4]), C3 (default [0, ∞)) and C4 (UP −1 without a lower bound: (−∞, −1]).
    let p = CscMatrix::from_triplets(4, 4, &[(0, 0, 2.0), (0, 1, -1.0), (1, 1, 4.0), (2, 3, 0.5)])
        .unwrap();
    let a = CscMatrix::from_triplets(
        9,
        4,
        &[
            (0, 0, 1.0),
            (1, 0, 2.0),
            (0, 1, 1.0),
            (2, 1, 1.0),
            (3, 1, 1.0),
            (5, 2, 1.0),
            (4, 2, 3.0),
            (1, 3, -1.0),
            (6, 0, 1.0),
            (7, 2, 1.0),
            (8, 3, 1.0),
        ],
    )
    .unwrap();
    let expected = Qp {
        p,
        q: vec![1.0, -2.0, 0.0, 0.0],
        a,
        // R1: L 10 range 4 → [6, 10]; R2: G 1 range −2 → [1, 3]; R3: E 2 range 1.5 → [2, 3.5];
        // R4: E 3 range −1.5 → [1.5, 3]; FREE; R5: E −1.
        l: vec![6.0, 1.0, 2.0, 1.5, -INF, -1.0, 0.0, 0.0, -INF],
        u: vec![10.0, 3.0, 3.5, 3.0, INF, -1.0, 4.0, INF, -1.0],
    };
    assert_eq!(qp, expected);
    assert_eq!(bits(&qp), bits(&expected));
}

#[test]
fn reads_crlf_line_endings() {
    let crlf = MM_TEXT.replace('\n', "\r\n");
    assert_eq!(read_str(&crlf).unwrap(), read_str(MM_TEXT).unwrap());
}

/// Fields that are not plain decimals, or with absurd exponents, fall back to `f64` arithmetic.
#[test]
fn ranges_with_infinite_or_extreme_fields() {
    let text = "\
ROWS
 N obj
 G g
 L l
COLUMNS
 x g 1 l 1
RHS
 rhs g 1 l 2
RANGES
 rng g inf l 1e-9223372036854775808
BOUNDS
 FR bnd x
ENDATA
";
    let (_, qp) = read_str(text).unwrap();
    assert_eq!((qp.l[0], qp.u[0]), (1.0, INF));
    assert_eq!((qp.l[1], qp.u[1]), (2.0, 2.0));
}

#[test]
fn reads_other_bound_types_and_optional_set_names() {
    let text = "\
NAME
ROWS
 N obj
 G r
COLUMNS
 a obj 1 r 1
 b r 1
 c r 1
 d r 1
 e r 1
 f r 1
RHS
 r 2
 other r 99
BOUNDS
 LO a -1
 UP a 1
 FX b 3.5
 MI c
 UP c 2
 PL d
 LO e 1
 UP e -2
 MI f 0
 UP other a 100
QUADOBJ
 a a 1
 a a 1
ENDATA
";
    // An explicit lower bound 1 is kept when a negative upper bound follows: [1, −2] is invalid.
    let e = read_str(text).unwrap_err();
    assert!(matches!(e, QpsError::InvalidProblem(_)), "{e}");
    let valid = text.replace(" UP e -2\n", " UP e 2\n");
    let (name, qp) = read_str(&valid).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(name, "");
    assert_eq!(qp.l[0], 2.0, "only the first RHS set is used");
    assert_eq!(qp.u[0], INF);
    // Bound rows: a [−1, 1], b [3.5, 3.5], c (−∞, 2], d [0, ∞), e [1, 2]; f is free (`MI f 0`,
    // a value after MI being ignored, and the `UP other …` line is in a second set) → no row.
    assert_eq!(qp.l[1..], [-1.0, 3.5, -INF, 0.0, 1.0]);
    assert_eq!(qp.u[1..], [1.0, 3.5, 2.0, INF, 2.0]);
    assert_eq!(qp.a.nrows, 6);
    // Duplicate QUADOBJ entries are summed.
    assert_eq!(qp.p.nzval, vec![2.0]);
}

#[test]
fn contradictory_bounds_are_an_invalid_problem() {
    let text = "ROWS\n N obj\nCOLUMNS\n x obj 1\nBOUNDS\n LO b x 1\n UP b x -2\nENDATA\n";
    let e = read_str(text).unwrap_err();
    assert!(matches!(e, QpsError::InvalidProblem(_)), "{e}");
}

#[test]
fn qmatrix_keeps_the_symmetric_part() {
    let text = "\
ROWS
 N obj
COLUMNS
 x obj 0
 y obj 0
BOUNDS
 FR b x
 FR b y
QMATRIX
 x x 2
 x y 1
 y x 1
 y y 4
ENDATA
";
    let (_, qp) = read_str(text).unwrap();
    assert_eq!(qp.p.to_dense(), vec![vec![2.0, 1.0], vec![0.0, 4.0]]);
    assert_eq!(qp.m(), 0);
}

fn err(text: &str) -> String {
    read_str(text).unwrap_err().to_string()
}

fn assert_has(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "{msg:?} lacks {p:?}");
    }
}

#[test]
fn unknown_row_in_columns_names_line_and_token() {
    let text = "NAME T\nROWS\n N obj\n L c0\nCOLUMNS\n x0 obj 1 c0 2\n x1 R9 1\nENDATA\n";
    let msg = err(text);
    assert_has(&msg, &["line 7", "unknown row", "`R9`"]);
}

#[test]
fn bad_number_names_line_and_token() {
    let text = "NAME T\nROWS\n N obj\n L c0\nCOLUMNS\n x0 obj 1 c0 1.0.0\nENDATA\n";
    let msg = err(text);
    assert_has(&msg, &["line 6", "bad number", "`1.0.0`"]);
    let nan = "ROWS\n N obj\n G c0\nCOLUMNS\n x0 c0 1\nRHS\n rhs c0 NaN\nENDATA\n";
    assert_has(&err(nan), &["line 7", "bad number", "`NaN`"]);
    let inf = "ROWS\n N obj\nCOLUMNS\n x0 obj inf\nENDATA\n";
    assert_has(&err(inf), &["line 4", "bad number", "`inf`"]);
}

#[test]
fn unknown_section_names_line_and_token() {
    let text = "NAME T\nROWS\n N obj\nCOLUMNS\n x0 obj 1\nSOS\nENDATA\n";
    let msg = err(text);
    assert_has(&msg, &["line 6", "unknown section", "`SOS`"]);
}

#[test]
fn other_errors_name_line_and_token() {
    let marker = "ROWS\n N obj\nCOLUMNS\n M1 'MARKER' 'INTORG'\n x obj 1\nENDATA\n";
    assert_has(&err(marker), &["line 4", "MARKER", "not supported"]);
    let unknown_col = "ROWS\n N obj\nCOLUMNS\n x obj 1\nQUADOBJ\n x zz 1\nENDATA\n";
    assert_has(&err(unknown_col), &["line 6", "unknown column", "`zz`"]);
    let bv = "ROWS\n N obj\nCOLUMNS\n x obj 1\nBOUNDS\n BV b x\nENDATA\n";
    assert_has(&err(bv), &["line 6", "`BV`", "not supported"]);
    let bad_bound = "ROWS\n N obj\nCOLUMNS\n x obj 1\nBOUNDS\n XX b x 1\nENDATA\n";
    assert_has(&err(bad_bound), &["line 6", "unknown bound type", "`XX`"]);
    let row_type = "ROWS\n N obj\n Q r\nENDATA\n";
    assert_has(&err(row_type), &["line 3", "unknown row type", "`Q`"]);
    let dup = "ROWS\n N obj\n L r\n G r\nCOLUMNS\nENDATA\n";
    assert_has(&err(dup), &["line 4", "`r`", "twice"]);
    let no_end = "ROWS\n N obj\nCOLUMNS\n x obj 1\n";
    assert_has(&err(no_end), &["line 5", "missing section ENDATA"]);
    let no_rows = "NAME T\nCOLUMNS\n x obj 1\nENDATA\n";
    assert_has(&err(no_rows), &["line 2", "missing section ROWS"]);
    let fields = "ROWS\n N obj\nCOLUMNS\n x obj\nENDATA\n";
    assert_has(&err(fields), &["line 4", "`x`", "malformed"]);
    let max = "NAME T\nOBJSENSE\n    MAX\nROWS\n N obj\nCOLUMNS\nENDATA\n";
    assert_has(&err(max), &["line 3", "`MAX`", "not supported"]);
}

#[test]
fn writer_rejects_invalid_input() {
    let mut qp = hand_made();
    assert!(write_qps(&qp, "two\nlines", Vec::new()).is_err());
    assert!(write_qps(&qp, " padded", Vec::new()).is_err());
    qp.l[2] = 9.0; // l > u
    let e = write_qps(&qp, "BAD", Vec::new()).unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
}
