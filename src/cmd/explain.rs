//! `mcl explain CODE`.

use mcl_compiler::codes;

pub fn run(code: Option<&str>) -> u8 {
    match code {
        None => {
            for c in codes::ALL {
                println!("{}  {}", c.code, c.title);
            }
            0
        }
        Some(code) => match codes::lookup(code) {
            Some(info) => {
                print!("{}", info.explanation);
                0
            }
            None => {
                eprintln!("error: `{code}` is not an MCL diagnostic code; `mcl explain` lists them all");
                2
            }
        },
    }
}
