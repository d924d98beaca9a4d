//! MCL (Mission Control Language) support for the [tree-sitter] parsing
//! library: the generated parser and the editor queries.
//!
//! ```
//! let mut parser = tree_sitter::Parser::new();
//! parser.set_language(&tree_sitter_mcl::LANGUAGE.into()).expect("load the MCL grammar");
//! let tree = parser.parse("mission { Goto( [24, 12] ) }", None).unwrap();
//! assert!(!tree.root_node().has_error());
//! ```
//!
//! [tree-sitter]: https://tree-sitter.github.io/

use tree_sitter_language::LanguageFn;

extern "C" {
    fn tree_sitter_mcl() -> *const ();
}

/// The tree-sitter [`LanguageFn`] of MCL.
// SAFETY: `tree_sitter_mcl` is the generated parser's language function
// (`src/parser.c`, compiled by build.rs): it takes nothing and returns a
// pointer to its static `TSLanguage`, as `LanguageFn::from_raw` requires.
pub const LANGUAGE: LanguageFn = unsafe { LanguageFn::from_raw(tree_sitter_mcl) };

/// The content of `src/node-types.json`.
pub const NODE_TYPES: &str = include_str!("../../src/node-types.json");

/// The syntax highlighting query.
pub const HIGHLIGHTS_QUERY: &str = include_str!("../../queries/highlights.scm");

/// The folding query.
pub const FOLDS_QUERY: &str = include_str!("../../queries/folds.scm");

/// The indentation query.
pub const INDENTS_QUERY: &str = include_str!("../../queries/indents.scm");

/// The scopes, definitions and references query.
pub const LOCALS_QUERY: &str = include_str!("../../queries/locals.scm");

#[cfg(test)]
mod tests {
    #[test]
    fn the_grammar_and_its_queries_load() {
        let language: tree_sitter::Language = super::LANGUAGE.into();
        let mut parser = tree_sitter::Parser::new();
        parser.set_language(&language).expect("load the MCL grammar");
        for q in [super::HIGHLIGHTS_QUERY, super::FOLDS_QUERY, super::INDENTS_QUERY, super::LOCALS_QUERY] {
            tree_sitter::Query::new(&language, q).expect("a valid query");
        }
    }
}
