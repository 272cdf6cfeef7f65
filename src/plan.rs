//! Which passes a frame runs: only those the scene and the settings call for.
//!
//! A [`Plan`] is a plain value computed from a scene's [`SceneInfo`] and the [`Settings`]; it
//! can be printed (`deep-gbuffer render --plan`) and tested. The renderer records exactly the
//! passes it lists, so a skipped pass issues no GPU work and has no timing.

use std::fmt;

use crate::scene::SceneInfo;
use crate::settings::{Layer1Variant, Settings};

/// The effects a user can switch on or off (`--effects`); the plan runs an enabled effect only
/// when the scene calls for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Effects {
    /// Ambient obscurance (needs an ambient term).
    pub ao: bool,
    /// Direct light (needs a light).
    pub direct: bool,
    /// Shadow maps (need direct light and a light that casts shadows).
    pub shadows: bool,
    /// Screen-space radiosity (needs a light or an emissive material).
    pub radiosity: bool,
    /// Screen-space reflections (need a reflective material).
    pub reflections: bool,
}

impl Default for Effects {
    fn default() -> Self {
        Effects { ao: true, direct: true, shadows: true, radiosity: true, reflections: true }
    }
}

impl Effects {
    /// Parses `auto` (everything the scene calls for) or a comma-separated list (`ao,direct`).
    pub fn parse(text: &str) -> crate::Result<Effects> {
        if text.trim() == "auto" {
            return Ok(Effects::default());
        }
        let mut e = Effects {
            ao: false,
            direct: false,
            shadows: false,
            radiosity: false,
            reflections: false,
        };
        for name in text.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            match name {
                "ao" => e.ao = true,
                "direct" => e.direct = true,
                "shadows" => e.shadows = true,
                "radiosity" => e.radiosity = true,
                "reflections" => e.reflections = true,
                other => {
                    return Err(crate::Error::setting(
                        "effects",
                        format!(
                            "unknown effect `{other}` (known: ao, direct, shadows, radiosity, reflections; or auto)"
                        ),
                    ));
                }
            }
        }
        Ok(e)
    }
}

/// Why an effect does or does not run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// It runs.
    Runs,
    /// Switched off in the settings.
    Disabled,
    /// The scene does not call for it (no ambient term, no light...).
    NotNeeded,
}

/// The passes of one frame and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Plan {
    /// G-buffer layers rasterized (layer 1 only when an effect reads it).
    pub layers: u32,
    /// Ambient obscurance.
    pub ao: Reason,
    /// Obscurance reads both layers.
    pub ao_two_layers: bool,
    /// Direct light.
    pub direct: Reason,
    /// Screen-space radiosity.
    pub radiosity: Reason,
    /// Screen-space reflections.
    pub reflections: Reason,
    /// Names of the lights that get shadow maps (pass `shadow.<name>` each).
    pub shadows: Vec<String>,
    /// Pass names in order, as `--timings` names them (steady state: a one-pass layer-1
    /// variant rasterizes both layers in `raster.layers` once it has a previous frame).
    pub passes: Vec<String>,
}

impl Plan {
    /// The plan for a scene with `info` under `settings`.
    pub fn new(info: &SceneInfo, settings: &Settings) -> Plan {
        let reason = |enabled: bool, needed: bool| match (enabled, needed) {
            (false, _) => Reason::Disabled,
            (true, false) => Reason::NotNeeded,
            (true, true) => Reason::Runs,
        };
        let ao =
            reason(settings.ao.enabled && settings.effects.ao, info.ambient.max_element() > 0.0);
        let direct = reason(settings.effects.direct, !info.lights.is_empty());
        let radiosity = reason(
            settings.radiosity.enabled && settings.effects.radiosity,
            !info.lights.is_empty() || info.emissive,
        );
        let reflections =
            reason(settings.reflections.enabled && settings.effects.reflections, info.reflective);
        let wants_layer1 = (ao == Reason::Runs && settings.ao.two_layers)
            || radiosity == Reason::Runs
            || reflections == Reason::Runs;
        let layers = match settings.layers {
            1 => 1,
            2 => 2,
            _ => 1 + u32::from(wants_layer1),
        };
        let mut passes = vec!["raster.clear".to_string()];
        if layers == 2 && settings.layer1 != Layer1Variant::TwoPass {
            passes.push("raster.layers".into());
        } else {
            passes.push("raster.layer0".into());
            if layers == 2 {
                passes.push("raster.layer1".into());
            }
        }
        passes.push("resolve".into());
        if ao == Reason::Runs {
            passes.extend(["pyramid", "ao"].map(String::from));
            if settings.ao.blur_radius > 0 {
                passes.push("ao.blur".into());
            }
        }
        let shadows: Vec<String> =
            if direct == Reason::Runs && settings.effects.shadows && settings.shadows.enabled {
                info.lights.iter().filter(|l| l.casts_shadows).map(|l| l.name.clone()).collect()
            } else {
                Vec::new()
            };
        passes.extend(shadows.iter().map(|name| format!("shadow.{name}")));
        if direct == Reason::Runs {
            passes.push("direct".into());
        }
        if radiosity == Reason::Runs {
            passes.extend(["radiosity", "radiosity.temporal"].map(String::from));
            if settings.radiosity.blur_radius > 0 {
                passes.push("radiosity.blur".into());
            }
        }
        if reflections == Reason::Runs {
            passes.push("reflections".into());
        }
        passes.push("composite".into());
        Plan {
            layers,
            ao,
            ao_two_layers: layers == 2 && settings.ao.two_layers,
            direct,
            radiosity,
            reflections,
            shadows,
            passes,
        }
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let why = |r: Reason| match r {
            Reason::Runs => "runs",
            Reason::Disabled => "off (disabled)",
            Reason::NotNeeded => "off (the scene does not call for it)",
        };
        writeln!(f, "layers:  {}", self.layers)?;
        writeln!(
            f,
            "ao:      {}{}",
            why(self.ao),
            if self.ao_two_layers { ", two layers" } else { "" }
        )?;
        writeln!(f, "direct:  {}", why(self.direct))?;
        writeln!(f, "radiosity: {}", why(self.radiosity))?;
        writeln!(f, "reflections: {}", why(self.reflections))?;
        if self.shadows.is_empty() {
            writeln!(f, "shadows: none")?;
        } else {
            writeln!(f, "shadows: {}", self.shadows.join(", "))?;
        }
        write!(f, "passes:  {}", self.passes.join(", "))
    }
}
