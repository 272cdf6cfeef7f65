//! A small WGSL preprocessor, shared by `build.rs` (validation) and the runtime (shader
//! creation): `#include "path"` (relative to `wgsl/`, each file once), and `#if NAME`,
//! `#if !NAME`, `#else`, `#endif` on defined names. Directive lines and inactive lines become empty
//! lines, so line numbers hold up to the first `#include`.

/// Expands `source` (the file `name`) with `defines`; `lookup` finds an included file's text.
pub fn preprocess<'a>(
    name: &str,
    source: &'a str,
    defines: &[&str],
    lookup: &dyn Fn(&str) -> Option<&'a str>,
) -> Result<String, String> {
    let mut out = String::with_capacity(source.len() * 2);
    let mut included: Vec<String> = Vec::new();
    expand(name, source, defines, lookup, &mut included, &mut out)?;
    Ok(out)
}

fn expand<'a>(
    name: &str,
    source: &'a str,
    defines: &[&str],
    lookup: &dyn Fn(&str) -> Option<&'a str>,
    included: &mut Vec<String>,
    out: &mut String,
) -> Result<(), String> {
    // Each entry: (this branch is active, some branch of this #if was taken, parent active).
    let mut stack: Vec<(bool, bool)> = Vec::new();
    let active = |stack: &[(bool, bool)]| stack.iter().all(|s| s.0);
    for (n, line) in source.lines().enumerate() {
        let trimmed = line.trim();
        let at = || format!("{name}:{}", n + 1);
        if let Some(cond) = trimmed.strip_prefix("#if ") {
            let cond = cond.trim();
            let (negate, sym) = match cond.strip_prefix('!') {
                Some(s) => (true, s.trim()),
                None => (false, cond),
            };
            let value = defines.contains(&sym) != negate;
            stack.push((value, value));
            out.push('\n');
        } else if trimmed == "#else" {
            let top = stack.last_mut().ok_or_else(|| format!("{}: #else without #if", at()))?;
            *top = (!top.1, true);
            out.push('\n');
        } else if trimmed == "#endif" {
            stack.pop().ok_or_else(|| format!("{}: #endif without #if", at()))?;
            out.push('\n');
        } else if let Some(rest) = trimmed.strip_prefix("#include") {
            if active(&stack) {
                let file = rest.trim().trim_matches('"');
                if !included.iter().any(|f| f == file) {
                    included.push(file.to_string());
                    let text =
                        lookup(file).ok_or_else(|| format!("{}: cannot include `{file}`", at()))?;
                    expand(file, text, defines, lookup, included, out)?;
                }
            }
            out.push('\n');
        } else if active(&stack) {
            out.push_str(line);
            out.push('\n');
        } else {
            out.push('\n');
        }
    }
    if !stack.is_empty() {
        return Err(format!("{name}: #if without #endif"));
    }
    Ok(())
}

/// The defines a kernel declares on its `// defines: A B C` line (none without one): the only
/// names it may be compiled with, and the combinations `build.rs` validates.
pub fn declared_defines(source: &str) -> Vec<&str> {
    source
        .lines()
        .find_map(|l| l.trim().strip_prefix("// defines:"))
        .map(|rest| rest.split_whitespace().collect())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lookup(name: &str) -> Option<&'static str> {
        match name {
            "a.wgsl" => Some("const A = 1;\n#include \"b.wgsl\""),
            "b.wgsl" => Some("#if X\nconst B = 2;\n#else\nconst B = 3;\n#endif"),
            _ => None,
        }
    }

    fn code(s: &str) -> Vec<&str> {
        s.lines().map(str::trim).filter(|l| !l.is_empty()).collect()
    }

    #[test]
    fn includes_once_and_selects_branches() {
        let src = "#include \"a.wgsl\"\n#include \"b.wgsl\"\n#if !X\nfn f() {}\n#endif";
        assert_eq!(
            code(&preprocess("k", src, &["X"], &lookup).unwrap()),
            ["const A = 1;", "const B = 2;"]
        );
        assert_eq!(
            code(&preprocess("k", src, &[], &lookup).unwrap()),
            ["const A = 1;", "const B = 3;", "fn f() {}"]
        );
    }

    #[test]
    fn nested_conditions() {
        let src = "#if X\n#if Y\nxy\n#else\nx\n#endif\n#endif";
        assert_eq!(code(&preprocess("k", src, &["X", "Y"], &lookup).unwrap()), ["xy"]);
        assert_eq!(code(&preprocess("k", src, &["X"], &lookup).unwrap()), ["x"]);
        assert!(code(&preprocess("k", src, &["Y"], &lookup).unwrap()).is_empty());
    }

    #[test]
    fn errors_name_the_line() {
        assert_eq!(preprocess("k", "#endif", &[], &lookup).unwrap_err(), "k:1: #endif without #if");
        assert!(
            preprocess("k", "\n#include \"none.wgsl\"", &[], &lookup)
                .unwrap_err()
                .starts_with("k:2:")
        );
        assert!(preprocess("k", "#if X", &[], &lookup).is_err());
    }

    #[test]
    fn keeps_line_numbers() {
        let out = preprocess("k", "#if X\na\n#endif\nb", &[], &lookup).unwrap();
        assert_eq!(out.lines().nth(3), Some("b"));
        assert_eq!(declared_defines("// x\n// defines: A B\n"), ["A", "B"]);
    }
}
