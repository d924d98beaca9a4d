//! Generators of classic STRIPS benchmark problems (typed PDDL, unit cost):
//! gripper, blocksworld (4 operators), logistics and miconic (STRIPS
//! version). Deterministic: the same arguments give the same files. Used by
//! the pyperplan oracle test and the benchmark (`mcl-plan-gen`).

/// splitmix64: a small deterministic generator.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x6D63_6C2D_706C_616E)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `0..n` (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
    pub fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            let j = self.below(i + 1);
            v.swap(i, j);
        }
    }
}

/// A generated instance.
#[derive(Clone, Debug)]
pub struct Instance {
    pub name: String,
    pub domain: String,
    pub problem: String,
}

pub const GRIPPER_DOMAIN: &str = "\
(define (domain gripper)
  (:requirements :strips :typing)
  (:types room ball gripper)
  (:predicates (at-robby ?r - room) (at ?b - ball ?r - room)
               (free ?g - gripper) (carry ?b - ball ?g - gripper))
  (:action move
    :parameters (?from ?to - room)
    :precondition (at-robby ?from)
    :effect (and (at-robby ?to) (not (at-robby ?from))))
  (:action pick
    :parameters (?obj - ball ?room - room ?g - gripper)
    :precondition (and (at ?obj ?room) (at-robby ?room) (free ?g))
    :effect (and (carry ?obj ?g) (not (at ?obj ?room)) (not (free ?g))))
  (:action drop
    :parameters (?obj - ball ?room - room ?g - gripper)
    :precondition (and (carry ?obj ?g) (at-robby ?room))
    :effect (and (at ?obj ?room) (free ?g) (not (carry ?obj ?g)))))
";

/// `balls` balls in room A to carry to room B with two grippers.
/// Optimal plan length: 3·balls − 1 for an even number of balls, 3·balls for odd.
pub fn gripper(balls: usize) -> Instance {
    let names: Vec<String> = (1..=balls).map(|i| format!("ball{i}")).collect();
    let mut p = format!("(define (problem gripper-{balls})\n  (:domain gripper)\n  (:objects rooma roomb - room left right - gripper {} - ball)\n", names.join(" "));
    p.push_str("  (:init (at-robby rooma) (free left) (free right)");
    for b in &names {
        p.push_str(&format!("\n         (at {b} rooma)"));
    }
    p.push_str(")\n  (:goal (and");
    for b in &names {
        p.push_str(&format!(" (at {b} roomb)"));
    }
    p.push_str(")))\n");
    Instance { name: format!("gripper-{balls}"), domain: GRIPPER_DOMAIN.to_string(), problem: p }
}

pub const BLOCKSWORLD_DOMAIN: &str = "\
(define (domain blocksworld)
  (:requirements :strips :typing)
  (:types block)
  (:predicates (on ?x ?y - block) (ontable ?x - block) (clear ?x - block)
               (handempty) (holding ?x - block))
  (:action pick-up
    :parameters (?x - block)
    :precondition (and (clear ?x) (ontable ?x) (handempty))
    :effect (and (not (ontable ?x)) (not (clear ?x)) (not (handempty)) (holding ?x)))
  (:action put-down
    :parameters (?x - block)
    :precondition (holding ?x)
    :effect (and (not (holding ?x)) (clear ?x) (handempty) (ontable ?x)))
  (:action stack
    :parameters (?x ?y - block)
    :precondition (and (holding ?x) (clear ?y))
    :effect (and (not (holding ?x)) (not (clear ?y)) (clear ?x) (handempty) (on ?x ?y)))
  (:action unstack
    :parameters (?x ?y - block)
    :precondition (and (on ?x ?y) (clear ?x) (handempty))
    :effect (and (holding ?x) (clear ?y) (not (clear ?x)) (not (handempty)) (not (on ?x ?y)))))
";

/// Random towers: each tower is listed bottom first.
fn towers(rng: &mut Rng, n: usize) -> Vec<Vec<usize>> {
    let mut order: Vec<usize> = (0..n).collect();
    rng.shuffle(&mut order);
    let mut out: Vec<Vec<usize>> = Vec::new();
    for b in order {
        // Start a new tower with probability 1/3 (always for the first block).
        if out.is_empty() || rng.below(3) == 0 {
            out.push(vec![b]);
        } else {
            let k = rng.below(out.len());
            out[k].push(b);
        }
    }
    out
}

/// `blocks` blocks from one random arrangement to another (goal: the `on` facts).
pub fn blocksworld(blocks: usize, seed: u64) -> Instance {
    let mut rng = Rng::new(seed);
    let name = |b: usize| format!("b{}", b + 1);
    let init = towers(&mut rng, blocks);
    let mut goal = towers(&mut rng, blocks);
    if goal.iter().all(|t| t.len() == 1) && blocks > 1 {
        // Make sure the goal says something.
        let b = goal.pop().unwrap_or_default();
        goal[0].extend(b);
    }
    let objs: Vec<String> = (0..blocks).map(name).collect();
    let mut p = format!("(define (problem blocks-{blocks}-{seed})\n  (:domain blocksworld)\n  (:objects {} - block)\n  (:init (handempty)", objs.join(" "));
    for t in &init {
        p.push_str(&format!("\n         (ontable {})", name(t[0])));
        for w in t.windows(2) {
            p.push_str(&format!(" (on {} {})", name(w[1]), name(w[0])));
        }
        p.push_str(&format!(" (clear {})", name(*t.last().unwrap_or(&t[0]))));
    }
    p.push_str(")\n  (:goal (and");
    for t in &goal {
        for w in t.windows(2) {
            p.push_str(&format!(" (on {} {})", name(w[1]), name(w[0])));
        }
    }
    p.push_str(")))\n");
    Instance { name: format!("blocks-{blocks}-{seed}"), domain: BLOCKSWORLD_DOMAIN.to_string(), problem: p }
}

pub const LOGISTICS_DOMAIN: &str = "\
(define (domain logistics)
  (:requirements :strips :typing)
  (:types truck airplane - vehicle
          package vehicle - physobj
          airport location - place
          city place physobj - object)
  (:predicates (in-city ?loc - place ?city - city)
               (at ?obj - physobj ?loc - place)
               (in ?pkg - package ?veh - vehicle))
  (:action load-truck
    :parameters (?pkg - package ?truck - truck ?loc - place)
    :precondition (and (at ?truck ?loc) (at ?pkg ?loc))
    :effect (and (not (at ?pkg ?loc)) (in ?pkg ?truck)))
  (:action load-airplane
    :parameters (?pkg - package ?airplane - airplane ?loc - place)
    :precondition (and (at ?pkg ?loc) (at ?airplane ?loc))
    :effect (and (not (at ?pkg ?loc)) (in ?pkg ?airplane)))
  (:action unload-truck
    :parameters (?pkg - package ?truck - truck ?loc - place)
    :precondition (and (at ?truck ?loc) (in ?pkg ?truck))
    :effect (and (not (in ?pkg ?truck)) (at ?pkg ?loc)))
  (:action unload-airplane
    :parameters (?pkg - package ?airplane - airplane ?loc - place)
    :precondition (and (in ?pkg ?airplane) (at ?airplane ?loc))
    :effect (and (not (in ?pkg ?airplane)) (at ?pkg ?loc)))
  (:action drive-truck
    :parameters (?truck - truck ?loc-from - place ?loc-to - place ?city - city)
    :precondition (and (at ?truck ?loc-from) (in-city ?loc-from ?city) (in-city ?loc-to ?city))
    :effect (and (not (at ?truck ?loc-from)) (at ?truck ?loc-to)))
  (:action fly-airplane
    :parameters (?airplane - airplane ?loc-from - airport ?loc-to - airport)
    :precondition (at ?airplane ?loc-from)
    :effect (and (not (at ?airplane ?loc-from)) (at ?airplane ?loc-to))))
";

/// `cities` cities of `size` places each (the first an airport), one truck
/// per city, `airplanes` airplanes and `packages` packages with random
/// origins and destinations.
pub fn logistics(cities: usize, size: usize, airplanes: usize, packages: usize, seed: u64) -> Instance {
    let mut rng = Rng::new(seed);
    let size = size.max(1);
    let cities = cities.max(1);
    let place = |c: usize, k: usize| if k == 0 { format!("apt{}", c + 1) } else { format!("pos{}-{}", c + 1, k) };
    let mut objs = String::new();
    let all_places: Vec<(usize, usize)> = (0..cities).flat_map(|c| (0..size).map(move |k| (c, k))).collect();
    objs.push_str(&(0..cities).map(|c| format!("city{}", c + 1)).collect::<Vec<_>>().join(" "));
    objs.push_str(" - city\n           ");
    objs.push_str(&(0..cities).map(|c| place(c, 0)).collect::<Vec<_>>().join(" "));
    objs.push_str(" - airport\n           ");
    let locs: Vec<String> = all_places.iter().filter(|(_, k)| *k > 0).map(|&(c, k)| place(c, k)).collect();
    if !locs.is_empty() {
        objs.push_str(&locs.join(" "));
        objs.push_str(" - location\n           ");
    }
    objs.push_str(&(0..cities).map(|c| format!("truck{}", c + 1)).collect::<Vec<_>>().join(" "));
    objs.push_str(" - truck\n           ");
    if airplanes > 0 {
        objs.push_str(&(0..airplanes).map(|a| format!("plane{}", a + 1)).collect::<Vec<_>>().join(" "));
        objs.push_str(" - airplane\n           ");
    }
    objs.push_str(&(0..packages).map(|p| format!("pkg{}", p + 1)).collect::<Vec<_>>().join(" "));
    objs.push_str(" - package");
    let mut init = Vec::new();
    for &(c, k) in &all_places {
        init.push(format!("(in-city {} city{})", place(c, k), c + 1));
    }
    for c in 0..cities {
        init.push(format!("(at truck{} {})", c + 1, place(c, rng.below(size))));
    }
    for a in 0..airplanes {
        init.push(format!("(at plane{} {})", a + 1, place(rng.below(cities.max(1)), 0)));
    }
    let mut goal = Vec::new();
    for p in 0..packages {
        let (c, k) = all_places[rng.below(all_places.len())];
        init.push(format!("(at pkg{} {})", p + 1, place(c, k)));
        let (c2, k2) = all_places[rng.below(all_places.len())];
        goal.push(format!("(at pkg{} {})", p + 1, place(c2, k2)));
    }
    let name = format!("logistics-{cities}-{size}-{airplanes}-{packages}-{seed}");
    let problem = format!(
        "(define (problem {name})\n  (:domain logistics)\n  (:objects {objs})\n  (:init {})\n  (:goal (and {})))\n",
        init.join("\n         "),
        goal.join(" ")
    );
    Instance { name, domain: LOGISTICS_DOMAIN.to_string(), problem }
}

pub const MICONIC_DOMAIN: &str = "\
(define (domain miconic)
  (:requirements :strips :typing)
  (:types passenger floor)
  (:predicates (origin ?person - passenger ?floor - floor)
               (destin ?person - passenger ?floor - floor)
               (above ?floor1 - floor ?floor2 - floor)
               (boarded ?person - passenger)
               (served ?person - passenger)
               (lift-at ?floor - floor))
  (:action board
    :parameters (?f - floor ?p - passenger)
    :precondition (and (lift-at ?f) (origin ?p ?f))
    :effect (boarded ?p))
  (:action depart
    :parameters (?f - floor ?p - passenger)
    :precondition (and (lift-at ?f) (destin ?p ?f) (boarded ?p))
    :effect (and (not (boarded ?p)) (served ?p)))
  (:action up
    :parameters (?f1 - floor ?f2 - floor)
    :precondition (and (lift-at ?f1) (above ?f1 ?f2))
    :effect (and (lift-at ?f2) (not (lift-at ?f1))))
  (:action down
    :parameters (?f1 - floor ?f2 - floor)
    :precondition (and (lift-at ?f1) (above ?f2 ?f1))
    :effect (and (lift-at ?f2) (not (lift-at ?f1)))))
";

/// An elevator with `floors` floors and `passengers` passengers with random
/// origin and destination floors (distinct); the lift starts at the ground floor.
pub fn miconic(floors: usize, passengers: usize, seed: u64) -> Instance {
    let floors = floors.max(2);
    let mut rng = Rng::new(seed);
    let fname = |f: usize| format!("f{f}");
    let mut init = Vec::new();
    for i in 0..floors {
        for j in i + 1..floors {
            init.push(format!("(above {} {})", fname(i), fname(j)));
        }
    }
    init.push(format!("(lift-at {})", fname(0)));
    let mut goal = Vec::new();
    for p in 0..passengers {
        let o = rng.below(floors);
        let mut d = rng.below(floors - 1);
        if d >= o {
            d += 1;
        }
        init.push(format!("(origin p{p} {})", fname(o)));
        init.push(format!("(destin p{p} {})", fname(d)));
        goal.push(format!("(served p{p})"));
    }
    let name = format!("miconic-{floors}-{passengers}-{seed}");
    let problem = format!(
        "(define (problem {name})\n  (:domain miconic)\n  (:objects {} - floor {} - passenger)\n  (:init {})\n  (:goal (and {})))\n",
        (0..floors).map(fname).collect::<Vec<_>>().join(" "),
        (0..passengers).map(|p| format!("p{p}")).collect::<Vec<_>>().join(" "),
        init.join("\n         "),
        goal.join(" ")
    );
    Instance { name, domain: MICONIC_DOMAIN.to_string(), problem }
}

/// The logistics domain with action costs (load/unload 1, drive 3, fly 10)
/// and the same problem with `(:metric minimize (total-cost))`: exercises
/// uniform-cost search and A* with general costs.
pub fn logistics_with_costs(cities: usize, size: usize, airplanes: usize, packages: usize, seed: u64) -> Instance {
    let base = logistics(cities, size, airplanes, packages, seed);
    let mut d = base.domain.replace("(:requirements :strips :typing)", "(:requirements :strips :typing :action-costs)");
    d = d.replace(
        "(in ?pkg - package ?veh - vehicle))",
        "(in ?pkg - package ?veh - vehicle))\n  (:functions (total-cost) - number)",
    );
    // Each action's effect is `:effect (and ...))`: add the cost before the
    // `)` that closes the `and`.
    let mut out = String::new();
    for (k, part) in d.split("(:action ").enumerate() {
        if k == 0 {
            out.push_str(part);
            continue;
        }
        let cost = if part.starts_with("drive") {
            3
        } else if part.starts_with("fly") {
            10
        } else {
            1
        };
        let eff = part.find(":effect (and").map(|e| e + ":effect ".len()).unwrap_or(0);
        // Find the `)` that closes the `(and` at `eff`.
        let mut depth = 0i32;
        let mut close = part.len();
        for (i, c) in part[eff..].char_indices() {
            match c {
                '(' => depth += 1,
                ')' => {
                    depth -= 1;
                    if depth == 0 {
                        close = eff + i;
                        break;
                    }
                }
                _ => {}
            }
        }
        out.push_str("(:action ");
        out.push_str(&part[..close]);
        out.push_str(&format!(" (increase (total-cost) {cost})"));
        out.push_str(&part[close..]);
    }
    let p = base.problem.replacen("(define (problem ", "(define (problem costs-", 1);
    let p = match p.rfind(')') {
        Some(i) => format!("{}\n  (:metric minimize (total-cost)))\n", p[..i].trim_end()),
        None => p,
    };
    Instance { name: format!("costs-{}", base.name), domain: out, problem: p }
}

/// Writes `domain.pddl` and `problem.pddl` of `inst` into `dir`.
pub fn write(inst: &Instance, dir: &std::path::Path) -> std::io::Result<(std::path::PathBuf, std::path::PathBuf)> {
    std::fs::create_dir_all(dir)?;
    let d = dir.join("domain.pddl");
    let p = dir.join("problem.pddl");
    std::fs::write(&d, &inst.domain)?;
    std::fs::write(&p, &inst.problem)?;
    Ok((d, p))
}
