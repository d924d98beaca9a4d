//! The vehicle a bridge file is checked against, from the programs of the
//! compiler's database (`mcl_compiler::interface::vehicle_interface`):
//! used by `mcl check --ros2`, `mcl run --ros2`, `mcl plan --run --ros2`
//! and the language server.

use super::check::{Vehicle, VehiclePrimitive};
use mcl_compiler::interface::vehicle_interface;
use mcl_compiler::{Db, SourceFile};

/// The primitives of the programs rooted at `roots`, merged by name.
pub fn vehicle_of(db: &dyn Db, roots: &[SourceFile]) -> Vehicle {
    let mut v = Vehicle::default();
    for &root in roots {
        for p in vehicle_interface(db, root).primitives {
            let i = match v.primitives.iter().position(|q| q.name == p.primitive) {
                Some(i) => i,
                None => {
                    v.primitives.push(VehiclePrimitive { name: p.primitive.clone(), ..Default::default() });
                    v.primitives.len() - 1
                }
            };
            let q = &mut v.primitives[i];
            for c in p.commands {
                if !q.commands.iter().any(|(n, _)| *n == c.command) {
                    q.commands.push((c.command, c.params));
                }
            }
            for e in p.events {
                if !q.events.contains(&e.event) {
                    q.events.push(e.event);
                }
            }
        }
    }
    v
}
