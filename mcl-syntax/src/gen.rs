//! A deterministic generator of large, well-formed and semantically valid MCL
//! programs, for benchmarks and tests of every layer.
//!
//! [`program`] writes one self-contained file: a vehicle (actions, events, the
//! seed's `AchieveOneGoal` pattern, its timed variant, an instantaneous
//! pattern and one task per primitive) followed by as many missions as it
//! takes to reach the requested number of lines. The missions use every
//! control structure, nested, with labels, every kind of call argument
//! (identifiers, negative and decimal numbers, strings, lists and tagged
//! lists), parametrised missions and `mcl_plan_op` operators, and a final
//! `constraints` block. Every name it uses is defined, every call has the
//! arity of its task, every `v:` parameter of an action and every timed
//! transition's delay parameter appears in the header of the tasks that use
//! them, and labels are unique within their mission.
//!
//! The output depends only on `(lines, seed)`; it uses no external crate.

use std::fmt::Write as _;

/// A small deterministic pseudo-random generator (SplitMix64), for
/// generated programs and the tests that make their own.
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// A number in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    /// True `percent` times in 100.
    pub fn chance(&mut self, percent: u64) -> bool {
        self.next_u64() % 100 < percent
    }
    /// One element of a non-empty slice.
    pub fn pick<'a, T>(&mut self, xs: &'a [T]) -> &'a T {
        &xs[self.below(xs.len())]
    }
    /// Shuffles `xs` in place (Fisher-Yates).
    pub fn shuffle<T>(&mut self, xs: &mut [T]) {
        for i in (1..xs.len()).rev() {
            xs.swap(i, self.below(i + 1));
        }
    }
}

/// The kind of value a task parameter takes.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Arg {
    /// A way-point: `[x, y]` or `[x, y, z]`.
    WayPoint,
    /// A path: `path[[x, y], ...]`.
    Path,
    /// A number, possibly negative or decimal.
    Num,
    /// A time-out in seconds (a positive integer).
    Timeout,
    /// `"achieve"` or `"keep"`.
    Mode,
    /// `"auto"` or `"manual"`.
    Control,
    /// A string describing an object.
    Description,
}

/// One primitive of the vehicle and the task that supervises it.
struct Prim {
    /// Task name; the primitive is `<name>Primitive`, the actions
    /// `enable<name>`/`disable<name>`, the events `event<name>Ok`/`Fail`.
    name: &'static str,
    /// Task parameters and the kind of value each takes.
    params: &'static [(&'static str, Arg)],
    /// Whether the task uses the timed pattern (then `timeout` is a parameter
    /// that only the pattern uses).
    timed: bool,
    /// Whether the task may be used as a loop or if condition (a check that
    /// ends quickly in ok or fail).
    check: bool,
}

const PRIMS: &[Prim] = &[
    Prim { name: "Goto", params: &[("way-point", Arg::WayPoint)], timed: false, check: false },
    Prim { name: "Trajectory", params: &[("velocity", Arg::Num), ("path", Arg::Path)], timed: false, check: false },
    Prim { name: "Depth", params: &[("depth", Arg::Num), ("mode", Arg::Mode)], timed: false, check: false },
    Prim {
        name: "Altitude",
        params: &[("altitude", Arg::Num), ("timeout", Arg::Timeout), ("mode", Arg::Mode)],
        timed: true,
        check: false,
    },
    Prim {
        name: "Heading",
        params: &[("angle", Arg::Num), ("timeout", Arg::Timeout), ("mode", Arg::Mode), ("control", Arg::Control)],
        timed: true,
        check: false,
    },
    Prim { name: "SearchPattern", params: &[("timeout", Arg::Timeout)], timed: true, check: false },
    Prim { name: "Search", params: &[("object_description", Arg::Description)], timed: false, check: true },
    Prim { name: "Surface", params: &[], timed: false, check: false },
    Prim { name: "EmergencySurface", params: &[], timed: false, check: false },
    Prim { name: "StationKeeping", params: &[], timed: false, check: false },
    Prim { name: "InitializeVehicle", params: &[], timed: false, check: false },
    Prim { name: "StopVehicle", params: &[], timed: false, check: false },
    Prim { name: "TakeImages", params: &[], timed: false, check: false },
    Prim { name: "Alarm", params: &[], timed: false, check: true },
    Prim { name: "InvalidPositioning", params: &[], timed: false, check: true },
    Prim { name: "BatteryOk", params: &[], timed: false, check: true },
    Prim { name: "SurveyDone", params: &[], timed: false, check: true },
    Prim { name: "GetPositionFix", params: &[], timed: false, check: false },
    Prim { name: "SendData", params: &[], timed: false, check: false },
    Prim { name: "ReceiveData", params: &[], timed: false, check: false },
];

/// The places, transitions and arcs of the seed's `AchieveOneGoal` (Extract 5.2).
const ACHIEVE_ONE_GOAL: &str = "\
        places {
            begin.1; abort.1; ok.1; fail.1; is_exe; is_ok; is_fail; enable; disable;
            off(1); exe; primitive_ok; primitive_fail;
        }
        transitions {
            TT0; TT1; TT2; TT3; T0; T1; T2; T3; T6; T7;
        }
        arcs {
            begin.1 -> TT0; off -> TT0; TT0 -> is_exe; TT0 -> enable;
            enable -> T0; T0 -> exe;
            exe -> T1; exe -> T2; exe -> T3;
            T1 -> off; T6 -> off; T7 -> off;
            T2 -> primitive_ok; T2 -> is_ok;
            T3 -> primitive_fail; T3 -> is_fail;
            primitive_ok -> T6; primitive_fail -> T7;
            disable -> T1; disable -> T6; disable -> T7;
            abort.1 -> TT1; is_exe -> TT1; TT1 -> disable;
            is_exe -> TT2; is_ok -> TT2; TT2 -> disable; TT2 -> ok.1;
            is_exe -> TT3; is_fail -> TT3; TT3 -> disable; TT3 -> fail.1;
        }
";

/// `AchieveOneGoal` plus the time-out transition of figure 4.7.
const ACHIEVE_ONE_GOAL_TIMED: &str = "\
        places {
            begin.1; abort.1; ok.1; fail.1; is_exe; is_ok; is_fail; enable; disable;
            off(1); exe; primitive_ok; primitive_fail;
        }
        transitions {
            TT0; TT1; TT2; TT3; T0; T1; T2; T3; T6; T7; TO(timeout);
        }
        arcs {
            begin.1 -> TT0; off -> TT0; TT0 -> is_exe; TT0 -> enable;
            enable -> T0; T0 -> exe;
            exe -> T1; exe -> T2; exe -> T3;
            T1 -> off; T6 -> off; T7 -> off;
            T2 -> primitive_ok; T2 -> is_ok;
            T3 -> primitive_fail; T3 -> is_fail;
            primitive_ok -> T6; primitive_fail -> T7;
            disable -> T1; disable -> T6; disable -> T7;
            abort.1 -> TT1; is_exe -> TT1; TT1 -> disable;
            is_exe -> TT2; is_ok -> TT2; TT2 -> disable; TT2 -> ok.1;
            is_exe -> TT3; is_fail -> TT3; TT3 -> disable; TT3 -> fail.1;
            is_exe -> TO; TO -> disable; TO -> fail.1;
        }
";

/// An instantaneous block that always ends in ok (the seed's `Void`/`True`).
const INSTANT: &str = "\
        places {
            begin.1; abort.1; ok.1; fail.1;
        }
        transitions {
            T0; TA;
        }
        arcs {
            begin.1 -> T0; T0 -> ok.1;
            begin.1 -> TA; abort.1 -> TA;
        }
";

fn vehicle(out: &mut String) {
    out.push_str("// Generated by mcl_syntax::gen::program: a vehicle and many missions.\n\nactions {\n");
    for p in PRIMS {
        let mut enable = format!("    enable{n} = {n}Primitive( c: enable", n = p.name);
        for (param, _) in p.params.iter().filter(|(q, _)| *q != "timeout") {
            let _ = write!(enable, ", v: {param}");
        }
        let _ = writeln!(out, "{enable} );");
        let _ = writeln!(out, "    disable{n} = {n}Primitive( c: disable );", n = p.name);
    }
    out.push_str("    enableBeacon = BeaconPrimitive( c: enable, v: 4, v: -2.5, v: \"slow\" );\n");
    out.push_str("    disableBeacon = BeaconPrimitive( c: disable );\n}\n\nevents {\n");
    for p in PRIMS.iter().map(|p| p.name).chain(["Beacon"]) {
        let _ = writeln!(out, "    event{p}Ok; event{p}Fail;");
    }
    out.push_str("}\n\npattern {\n    AchieveOneGoal {\n");
    out.push_str(ACHIEVE_ONE_GOAL);
    out.push_str("    }\n    AchieveOneGoalTimed {\n");
    out.push_str(ACHIEVE_ONE_GOAL_TIMED);
    out.push_str("    }\n    Instant {\n");
    out.push_str(INSTANT);
    out.push_str("    }\n}\n\ntasks {\n");
    let task = |out: &mut String, name: &str, params: &[&str], pattern: &str| {
        if params.is_empty() {
            let _ = writeln!(out, "    {name}(): {pattern} {{");
        } else {
            let _ = writeln!(out, "    {name}( {} ): {pattern} {{", params.join(", "));
        }
        let _ = writeln!(out, "        a: enable{name} -> T0;");
        let _ = writeln!(out, "        a: disable{name} -> T1, T6, T7;");
        let _ = writeln!(out, "        e: event{name}Ok -> T2;");
        let _ = writeln!(out, "        e: event{name}Fail -> T3;");
        out.push_str("    }\n");
    };
    for p in PRIMS {
        let params: Vec<&str> = p.params.iter().map(|(q, _)| *q).collect();
        task(out, p.name, &params, if p.timed { "AchieveOneGoalTimed" } else { "AchieveOneGoal" });
    }
    task(out, "Beacon", &[], "AchieveOneGoal");
    out.push_str("    Void(): Instant { }\n}\n");
}

/// Writes missions; tracks labels so that constraints can refer to them.
struct Writer {
    rng: Rng,
    out: String,
    lines: usize,
    /// Labels of the current mission.
    label: usize,
    /// Parameters of the current parametrised mission, used as call arguments.
    params: Vec<&'static str>,
}

impl Writer {
    fn line(&mut self, indent: usize, text: &str) {
        for _ in 0..indent {
            self.out.push_str("    ");
        }
        self.out.push_str(text);
        self.out.push('\n');
        self.lines += 1;
    }

    fn number(&mut self) -> String {
        match self.rng.below(4) {
            0 => format!("{}", self.rng.below(100)),
            1 => format!("-{}", 1 + self.rng.below(50)),
            2 => format!("{}.{}", self.rng.below(40), 1 + self.rng.below(9)),
            _ => format!("-{}.{}", self.rng.below(10), 5),
        }
    }

    fn coord(&mut self) -> String {
        if !self.params.is_empty() && self.rng.chance(50) {
            return (*self.rng.pick(&self.params)).to_string();
        }
        self.number()
    }

    fn arg(&mut self, kind: Arg) -> String {
        match kind {
            Arg::WayPoint => {
                if self.rng.chance(50) {
                    format!("[{}, {}]", self.coord(), self.coord())
                } else {
                    format!("[{}, {}, {}]", self.coord(), self.coord(), self.coord())
                }
            }
            Arg::Path => {
                let n = 2 + self.rng.below(4);
                let pts: Vec<String> = (0..n).map(|_| format!("[{}, {}]", self.coord(), self.coord())).collect();
                format!("path[{}]", pts.join(", "))
            }
            Arg::Num => {
                if !self.params.is_empty() && self.rng.chance(30) {
                    (*self.rng.pick(&self.params)).to_string()
                } else if self.rng.chance(20) {
                    (*self.rng.pick(&["velocity", "cruise_depth", "$speed", "sonar/range"])).to_string()
                } else {
                    self.number()
                }
            }
            Arg::Timeout => format!("{}", 30 + 30 * self.rng.below(20)),
            Arg::Mode => (*self.rng.pick(&["\"achieve\"", "\"keep\""])).to_string(),
            Arg::Control => (*self.rng.pick(&["\"auto\"", "\"manual\""])).to_string(),
            Arg::Description => {
                (*self.rng.pick(&["\"cable\"", "\"red \\\"buoy\\\"\"", "\"rock\"", "\"pipe/joint\""])).to_string()
            }
        }
    }

    fn call_text(&mut self, p: &Prim) -> String {
        let args: Vec<String> = p.params.iter().map(|(_, k)| self.arg(*k)).collect();
        let mut s =
            if args.is_empty() { format!("{}()", p.name) } else { format!("{}( {} )", p.name, args.join(", ")) };
        if self.rng.chance(25) {
            self.label += 1;
            let _ = write!(s, " : l{}", self.label);
        }
        s
    }

    fn call(&mut self) -> String {
        match self.rng.below(100) {
            0..=7 => {
                self.label += 1;
                format!("Void() : l{}", self.label)
            }
            8..=11 => "Beacon()".to_string(),
            _ => {
                let p = self.rng.pick(PRIMS);
                self.call_text(p)
            }
        }
    }

    fn check(&mut self) -> String {
        let checks: Vec<&Prim> = PRIMS.iter().filter(|p| p.check).collect();
        let p = *self.rng.pick(&checks);
        self.call_text(p)
    }

    /// A monitor's condition: a check that the watched block, written from
    /// `self.out[body..]`, does not call (a task shared by the two makes
    /// them wait for each other, W0303), or the instantaneous `Void()`.
    fn watch(&mut self, body: usize) -> String {
        let text = &self.out[body..];
        let free: Vec<&Prim> = PRIMS.iter().filter(|p| p.check && !text.contains(&format!("{}(", p.name))).collect();
        if free.is_empty() {
            return "Void()".to_string();
        }
        let p = *self.rng.pick(&free);
        self.call_text(p)
    }

    /// A condition: a check, sometimes negated.
    fn cond(&mut self) -> String {
        let c = self.check();
        if self.rng.chance(30) {
            format!("not ( {c} )")
        } else {
            c
        }
    }

    /// A `;`-separated sequence of 1..=max statements; the last one has no `;`.
    fn seq(&mut self, indent: usize, depth: usize, max: usize) {
        let n = 1 + self.rng.below(max);
        for i in 0..n {
            self.stmt(indent, depth, i + 1 < n);
        }
    }

    fn stmt(&mut self, ind: usize, depth: usize, semi: bool) {
        let end = if semi { " ;" } else { "" };
        let kind = if depth == 0 { 0 } else { self.rng.below(14) };
        match kind {
            0..=3 => {
                let c = self.call();
                self.line(ind, &format!("{c}{end}"));
            }
            4 => {
                let c = self.cond();
                self.line(ind, &format!("if ( {c} ) {{"));
                self.seq(ind + 1, depth - 1, 3);
                self.line(ind, &format!("}}{end}"));
            }
            5 => {
                let c = self.cond();
                self.line(ind, &format!("if ( {c} ) {{"));
                self.seq(ind + 1, depth - 1, 3);
                self.line(ind, "} else {");
                self.seq(ind + 1, depth - 1, 3);
                self.line(ind, &format!("}}{end}"));
            }
            6 => {
                let c = self.cond();
                self.line(ind, &format!("while ( {c} ) {{"));
                self.seq(ind + 1, depth - 1, 3);
                self.line(ind, &format!("}}{end}"));
            }
            7 => {
                self.line(ind, "try {");
                self.seq(ind + 1, depth - 1, 4);
                self.line(ind, "} catch {");
                self.seq(ind + 1, depth - 1, 2);
                self.line(ind, &format!("}}{end}"));
            }
            8 | 9 => {
                let op = if kind == 8 { "and" } else { "or" };
                let n = 2 + self.rng.below(2);
                self.line(ind, "parallel {");
                for i in 0..n {
                    self.seq(ind + 1, depth - 1, 2);
                    if i + 1 < n {
                        self.line(ind, &format!("}} {op} {{"));
                    }
                }
                self.line(ind, &format!("}}{end}"));
            }
            10 => {
                let c = self.check();
                self.line(ind, &format!("not ( {c} ){end}"));
            }
            11 | 12 => {
                let kw = if kind == 11 { "condition" } else { "while_condition" };
                self.line(ind, "monitor {");
                let body = self.out.len();
                self.seq(ind + 1, depth - 1, 3);
                let c = self.watch(body);
                self.line(ind, &format!("}} {kw} ( {c} ) do {{"));
                self.seq(ind + 1, depth - 1, 2);
                self.line(ind, &format!("}}{end}"));
            }
            _ => {
                // A statement with a comment before it.
                self.line(ind, "// a comment between statements");
                let c = self.call();
                self.line(ind, &format!("{c}{end}"));
            }
        }
    }
}

/// Generates a well-formed, semantically valid MCL program of about `lines`
/// lines (never fewer than the ~360 lines of its vehicle part and first
/// mission). The same `(lines, seed)` always gives the same text.
pub fn program(lines: usize, seed: u64) -> String {
    let mut w = Writer {
        rng: Rng(seed ^ 0x4D43_4C21),
        out: String::with_capacity(lines * 28),
        lines: 0,
        label: 0,
        params: Vec::new(),
    };
    vehicle(&mut w.out);
    w.lines = w.out.lines().count();
    let mut starts: Vec<String> = Vec::new();
    let mut k = 0usize;
    // Leave room for the constraints block.
    let budget = lines.saturating_sub(3 + lines / 250);
    while k == 0 || w.lines < budget {
        k += 1;
        w.out.push('\n');
        w.lines += 1;
        w.label = 0;
        w.params.clear();
        match k % 10 {
            3 => {
                w.params = vec!["x", "y", "z"];
                w.line(0, &format!("mission Move{k}( x, y, z ) {{"));
                w.line(1, "Goto( [x, y, z] ) ;");
                w.seq(1, 2, 3);
            }
            7 => {
                w.params = vec!["x", "y"];
                w.line(0, &format!("mcl_plan_op GotoOp{k}( x, y ) {{"));
                w.line(1, "Goto( [x, y] ) ;");
                w.seq(1, 2, 2);
            }
            _ => {
                if k % 10 == 5 {
                    w.line(0, &format!("mission : m{k} [ auv at {} ] {{", k % 4));
                } else {
                    w.line(0, &format!("mission : m{k} {{"));
                }
                w.line(1, "Void() : start ;");
                starts.push(format!("m{k}"));
                if k == 1 {
                    // The first mission calls every task once, so that even
                    // a small program uses its whole vehicle.
                    w.line(1, "parallel {");
                    for (i, p) in PRIMS.iter().enumerate() {
                        let c = w.call_text(p);
                        w.line(2, &format!("{c}{}", if i + 1 < PRIMS.len() { " ;" } else { "" }));
                    }
                    w.line(1, "} and {");
                    w.line(2, "Beacon()");
                    w.line(1, "} ;");
                }
                w.seq(1, 3, 4);
            }
        }
        w.line(0, "}");
    }
    // Constraints on disjoint pairs of missions, on their first call, which
    // always runs: they cannot deadlock.
    w.out.push('\n');
    w.line(0, "constraints {");
    let mut i = 0;
    let mut n = 0;
    while i + 1 < starts.len() && n < 1 + starts.len() / 8 {
        let (a, b) = (&starts[i], &starts[i + 1]);
        let c = match n % 6 {
            0 => format!("order {{ {a}:start, {b}:start }}"),
            1 => format!("sync {{ {a}:start, {b}:start }}"),
            2 => format!("mutex {{ {a}:start, {b}:start }} = 1"),
            3 => format!("_order_ {{ {a}:start, {b}:start }}"),
            4 => format!("_sync_ {{ {a}:start, {b}:start }}"),
            _ => format!("_mutex_ {{ {a}:start, {b}:start }} = 1"),
        };
        w.line(1, &c);
        i += 2;
        n += 1;
    }
    w.line(0, "}");
    w.out
}

/// A small vehicle for generated missions (the random-mission property
/// tests): tasks `A(x)`, `B()`, `W()` that end ok or fail, `Timed(timeout)`
/// with a time-out, and the instantaneous `Void()`.
pub const TEST_VEHICLE: &str = r#"
actions {
    enableA = APrimitive( c: enable, v: x ); disableA = APrimitive( c: disable );
    enableB = BPrimitive( c: enable ); disableB = BPrimitive( c: disable );
    enableT = TPrimitive( c: enable, v: timeout ); disableT = TPrimitive( c: disable );
    enableW = WPrimitive( c: enable ); disableW = WPrimitive( c: disable );
}
events { aOk; aFail; bOk; bFail; tOk; tFail; wOk; wFail; }
tasks {
    A( x ): AchieveOneGoal { a: enableA -> T0; a: disableA -> T1, T6, T7; e: aOk -> T2; e: aFail -> T3; }
    B(): AchieveOneGoal { a: enableB -> T0; a: disableB -> T1, T6, T7; e: bOk -> T2; e: bFail -> T3; }
    Timed( timeout ): AchieveOneGoalTimed { a: enableT -> T0; a: disableT -> T1, T6, T7; e: tOk -> T2; e: tFail -> T3; }
    Void(): Instant { }
    W(): AchieveOneGoal { a: enableW -> T0; a: disableW -> T1, T6, T7; e: wOk -> T2; e: wFail -> T3; }
}
"#;

/// Text that matters to the parser (delimiters, keywords, quotes, comment
/// markers, whole small items): what random edits insert in the tests of
/// incremental parsing and of the language server.
pub const EDIT_PIECES: &[&str] = &[
    "",
    "{",
    "}",
    "(",
    ")",
    "[",
    "]",
    ";",
    "\"",
    "/*",
    "*/",
    "//",
    "mission",
    "tasks {",
    "mission : x {",
    "import",
    "events",
    ",",
    ":",
    "->",
    "x",
    " ",
    "\n",
    "é",
    "constraints {",
    "mcl_plan_op",
    "5",
    "#",
    "import \"a.mcl\"",
    "import \"v.mcl\";",
    "Goto( 1 )",
    "mutex { a:b, c:d } = 1",
    "e: ev -> T0;",
];

/// Text that mutations insert in the robustness tests (token soups, the
/// mutated corpus): delimiters, operators, literals good and bad, comment
/// markers, odd characters (NUL, BOM, emoji), every keyword and a few small
/// calls. A superset of what [`EDIT_PIECES`] holds for incremental edits.
pub const MUTATION_PIECES: &[&str] = &[
    "{",
    "}",
    "(",
    ")",
    "[",
    "]",
    ";",
    ":",
    ",",
    ".",
    "=",
    "->",
    "→",
    "-",
    "/",
    "$",
    "\"",
    "\"s\"",
    "\"open",
    "/*",
    "*/",
    "// c\n",
    "/* c */",
    "\n",
    " ",
    "\t",
    "\r\n",
    "0",
    "-2",
    "15.5",
    "1.",
    "007",
    "-0.5",
    ".5",
    "x",
    "way-point",
    "a/b",
    "$v",
    "P_X",
    "file.xml",
    "é",
    "#",
    "'",
    "≠",
    "\u{0}",
    "\u{feff}",
    "🦀",
    "import",
    "actions",
    "events",
    "pattern",
    "patterns",
    "tasks",
    "mission",
    "mcl_plan_op",
    "constraints",
    "places",
    "transitions",
    "arcs",
    "while",
    "if",
    "then",
    "else",
    "do",
    "parallel",
    "and",
    "or",
    "try",
    "catch",
    "not",
    "monitor",
    "condition",
    "while_condition",
    "c",
    "v",
    "a",
    "e",
    "at",
    "mutex",
    "order",
    "sync",
    "_mutex_",
    "_order_",
    "_sync_",
    "A()",
    "B( 1, [2, 3] ) : l",
    "{ A() }",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_and_sized() {
        let a = program(2000, 7);
        assert_eq!(a, program(2000, 7));
        assert_ne!(a, program(2000, 8));
        let n = a.lines().count();
        assert!((1900..=2200).contains(&n), "{n} lines");
    }

    #[test]
    fn parses_without_errors() {
        for seed in 0..5 {
            let text = program(1500, seed);
            let p = crate::parse(&text);
            assert!(p.errors.is_empty(), "seed {seed}: {:?}", p.errors.first());
        }
    }
}
