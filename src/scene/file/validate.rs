//! The scene-level keys of a scene file: `dim`, `eps`, `gravity`, `name`, `[solver]`,
//! `[dynamics]`, and the `[[body]]` list (names unique), before assembly. `[solver]` and
//! `[dynamics].scheme` are checked by the loader's [`RunRules`](super::RunRules).

use super::assemble::Header;
use super::schema::{DynamicsSpec, FileSpec, SolverSpec};
use super::{fmt_list, Ctx, SceneFile, SceneFileError};
use std::collections::HashMap;
use std::path::Path;

impl Ctx<'_> {
    /// The scene of a parsed scene file (`path` names it).
    pub(super) fn build(&self, spec: FileSpec, path: &Path) -> Result<SceneFile, SceneFileError> {
        let dim_line = self.line(spec.dim.span().start);
        let dim = *spec.dim.get_ref();
        if dim != 2 && dim != 3 {
            return Err(self.invalid(dim_line, "dim", dim, "must be 2 or 3"));
        }
        let dim = dim as usize;
        let eps_line = self.line(spec.eps.span().start);
        let eps = *spec.eps.get_ref();
        if !(eps > 0.0 && eps.is_finite()) {
            return Err(self.invalid(eps_line, "eps", eps, "must be finite and > 0"));
        }
        let gravity = match &spec.gravity {
            None => None,
            Some(g) => {
                let line = self.line(g.span().start);
                let v = g.get_ref();
                if v.len() != dim || v.iter().any(|c| !c.is_finite()) {
                    return Err(self.invalid(
                        line,
                        "gravity",
                        fmt_list(v),
                        format!("must be {dim} finite numbers"),
                    ));
                }
                v.iter().any(|&c| c != 0.0).then(|| (v.clone(), line))
            }
        };
        let solver = match spec.solver {
            None => SolverSpec::default(),
            Some(s) => {
                let line = self.line(s.span().start);
                let s = s.into_inner();
                self.refused(self.rules.check_solver(&s), line, "solver")?;
                s
            }
        };
        let dynamics = match spec.dynamics {
            None => DynamicsSpec::default(),
            Some(d) => {
                let line = self.line(d.span().start);
                let d = d.into_inner();
                if let Some(dt) = d.dt {
                    if !(dt > 0.0 && dt.is_finite()) {
                        return Err(self.invalid(
                            line,
                            "dynamics.dt",
                            dt,
                            "must be finite and > 0",
                        ));
                    }
                }
                if d.steps == Some(0) {
                    return Err(self.invalid(line, "dynamics.steps", 0, "must be ≥ 1"));
                }
                self.refused(self.rules.check_dynamics(&d), line, "dynamics")?;
                d
            }
        };
        if spec.body.is_empty() {
            return Err(self.invalid(1, "body", "[]", "the scene needs at least one [[body]]"));
        }
        let name = match &spec.name {
            Some(n) => {
                let v = n.get_ref();
                if v.is_empty() || v.contains(['/', '\\']) {
                    return Err(self.invalid(
                        self.line(n.span().start),
                        "name",
                        format!("{v:?}"),
                        "must be non-empty and contain no path separator",
                    ));
                }
                v.clone()
            }
            None => path
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("scene")
                .to_string(),
        };
        // bodies
        let mut loaded = Vec::with_capacity(spec.body.len());
        let mut specs = Vec::with_capacity(spec.body.len());
        let mut names: HashMap<String, usize> = HashMap::new();
        for (i, b) in spec.body.into_iter().enumerate() {
            let line = self.line(b.span().start);
            let b = b.into_inner();
            let key = format!("body[{i}]");
            if b.name.is_empty() {
                return Err(self.invalid(line, format!("{key}.name"), "\"\"", "must be non-empty"));
            }
            if let Some(j) = names.insert(b.name.clone(), i) {
                return Err(self.invalid(
                    line,
                    format!("{key}.name"),
                    format!("{:?}", b.name),
                    format!("body[{j}] has the same name"),
                ));
            }
            loaded.push(self.load_body(&b, i, line, dim)?);
            specs.push(b);
        }
        let header = Header {
            name,
            dim,
            eps,
            eps_line,
            gravity,
            contact: spec.contact,
            welds: spec.weld.unwrap_or_default(),
            solver,
            dynamics,
        };
        self.assemble(header, loaded, specs, path)
    }

    /// A [`Refusal`](super::Refusal) of the table `table` (at `line`) as the error naming
    /// `table.KEY`.
    fn refused(
        &self,
        r: Result<(), super::Refusal>,
        line: usize,
        table: &str,
    ) -> Result<(), SceneFileError> {
        r.map_err(|e| self.invalid(line, format!("{table}.{}", e.key), e.value, e.reason))
    }
}
