//! `#[aliases(a, b)]` on an `extern "C"` function: the function as written, and beside it
//! one function per alias with the same parameters that calls it. mesorve's UMAT is
//! `rve_umat` (in `rve.h`, which cbindgen generates from the written source and so cannot
//! take from a `macro_rules!` expansion) and the same function under the names hosts look
//! up, `umat_` and `UMAT`; with this attribute its 38 parameters are written once.
//!
//! No dependency: the item's tokens are read as they come (`fn NAME (PARAMS)`), each
//! parameter's name being the first identifier of its comma-separated part.

use proc_macro::{Delimiter, TokenStream, TokenTree};

/// Emits the function, then for each alias
/// `#[no_mangle] pub unsafe extern "C" fn ALIAS(PARAMS) { NAME(names) }`. The aliases are
/// not in the header: cbindgen reads the source, where they are not written.
#[proc_macro_attribute]
pub fn aliases(attr: TokenStream, item: TokenStream) -> TokenStream {
    let aliases: Vec<String> = attr
        .into_iter()
        .filter_map(|t| match t {
            TokenTree::Ident(i) => Some(i.to_string()),
            _ => None,
        })
        .collect();
    let tokens: Vec<TokenTree> = item.clone().into_iter().collect();
    let fn_at = tokens
        .iter()
        .position(|t| matches!(t, TokenTree::Ident(i) if i.to_string() == "fn"))
        .expect("#[aliases] goes on a function");
    let name = tokens[fn_at + 1].to_string();
    let params = match &tokens[fn_at + 2] {
        TokenTree::Group(g) if g.delimiter() == Delimiter::Parenthesis => g.stream(),
        _ => panic!("#[aliases]: `fn {name}` without a parameter list"),
    };
    let names = parameter_names(params.clone()).join(", ");
    let mut out = item.to_string();
    for alias in aliases {
        out.push_str(&format!(
            "\n#[allow(clippy::too_many_arguments, non_snake_case)]\n#[no_mangle]\n\
             pub unsafe extern \"C\" fn {alias}({params}) {{ {name}({names}) }}\n"
        ));
    }
    out.parse().expect("the aliases are valid Rust")
}

/// The first identifier of each top-level comma-separated part of a parameter list (a
/// type's own commas sit inside groups or angle brackets, which a UMAT's pointer types
/// do not have; a generic type is refused).
fn parameter_names(params: TokenStream) -> Vec<String> {
    let mut names = Vec::new();
    let mut expecting = true;
    for t in params {
        match t {
            TokenTree::Punct(p) if p.as_char() == '<' => {
                panic!("#[aliases]: generic parameter types are not supported")
            }
            TokenTree::Punct(p) if p.as_char() == ',' => expecting = true,
            TokenTree::Ident(i) if expecting && i.to_string() != "mut" => {
                names.push(i.to_string());
                expecting = false;
            }
            _ => {}
        }
    }
    names
}
