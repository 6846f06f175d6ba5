//! Entry points of the fuzz targets (`fuzz/`, run by `cargo fuzz`) and of their regression
//! test (`tests/fuzz_regressions.rs`, which replays the inputs kept in `fuzz/regressions/`).
//! Each feeds arbitrary bytes to a reader of user input; a panic or a stack overflow is a bug.

use std::sync::OnceLock;

use paracosm_generators::ParamSpace;

fn text(data: &[u8]) -> Option<&str> {
    std::str::from_utf8(data).ok()
}

fn study_space() -> &'static ParamSpace {
    static SPACE: OnceLock<ParamSpace> = OnceLock::new();
    SPACE.get_or_init(|| paracosm_scenarios::reference::scenario().space().clone())
}

/// A space file (TOML), a CSV test set (with and without a space), and an STL formula (as
/// `paracosm-cover stl` and `Stl(...)` read it).
pub fn inputs(data: &[u8]) {
    let Some(s) = text(data) else { return };
    let _ = paracosm_oracles::stl::parse(s);
    let _ = crate::cover::parse_space("fuzz.toml", s);
    let _ = crate::cover::parse_tests("fuzz.csv", s, false, None);
    let _ = crate::cover::parse_tests("fuzz.csv", s, false, Some(study_space()));
}

/// Lines of `results.jsonl`, as `--resume`/`report` and `paracosm-cover` read them.
pub fn results(data: &[u8]) {
    let Some(s) = text(data) else { return };
    for line in s.lines() {
        let _ = crate::record::RunRecord::from_line(line, study_space());
    }
    let _ = crate::cover::parse_tests("fuzz.jsonl", s, true, None);
    let _ = crate::cover::parse_tests("fuzz.jsonl", s, true, Some(study_space()));
}

/// A scenario program, or (an input that starts with `<`) an OpenDRIVE map ([`opendrive`]).
pub fn scenario(data: &[u8]) {
    let Some(s) = text(data) else { return };
    if s.trim_start().starts_with('<') {
        opendrive(data);
        return;
    }
    let _ = paracosm_scenarios::lang::load_source("fuzz.star", s, "fuzz");
}

/// An OpenDRIVE map as `OpenDrive(...)` reads it: checked, baked, its surface indexed, and a
/// route of up to 200 m planned from the middle of each of its first 16 driving lanes, each
/// turn taken in turn (the `opendrive` fuzz target; the repository's maps are its seeds).
pub fn opendrive(data: &[u8]) {
    use paracosm_engine::network::Turn;
    let Some(s) = text(data) else { return };
    let Ok(imported) = paracosm_engine::network::opendrive::import("fuzz.xodr", s) else {
        return;
    };
    let map = imported.map.clone();
    let mut network = paracosm_engine::Network::new();
    if network
        .add_map("OpenDrive fuzz", imported.map, 0.8)
        .is_err()
    {
        return;
    }
    let surface = paracosm_engine::network::Surface::new(&network);
    let _ = surface.edge_distance_m([0.0, 0.0]);
    let turns = [Turn::Straight, Turn::Left, Turn::Right];
    for (i, lane) in map
        .lanes
        .iter()
        .enumerate()
        .filter(|(_, l)| l.drivable)
        .take(16)
    {
        let (Some(first), Some(last)) = (lane.s.first(), lane.s.last()) else {
            continue;
        };
        let _ = map.route(i, 0.5 * (first + last), &turns[i % 3..i % 3 + 1], 200.0);
    }
}

/// An OpenSCENARIO file as `paracosm-fuzz xosc` reads it, in the role its root gives it:
/// - a parameter value distribution is read, its levels counted, and then read as a
///   variation file of [`FUZZ_TEMPLATE`] (saved beside it as `template.xosc`: the
///   distribution's `ScenarioFile` may name it), which checks its parameters and value sets
///   against the template's declarations;
/// - a catalog is saved as `catalogs/fuzz.xosc` and read through a scenario whose entities
///   are its vehicle, pedestrian and object entries (up to 8) and whose first entity's
///   controller is its first controller entry ([`catalog_template`]), so every seed catalog's
///   entries are read whatever their names;
/// - anything else is read as a scenario (its relative paths from an empty folder, so
///   catalogs and maps are not found).
///
/// It returns errors, never panics, loops or overflows the stack (the `openscenario` fuzz
/// target; the ALKS suite, the hostile files and `fuzz/regressions/openscenario/` are its
/// seeds). The files go to a folder of the system's temporary folder named by the process
/// and thread, rewritten for each input.
pub fn openscenario(data: &[u8]) {
    let Some(s) = text(data) else { return };
    let text = paracosm_openscenario::Text::new("fuzz.xosc", s);
    let (is_variation, catalog) = match text.parse() {
        Ok(doc) => (
            paracosm_openscenario::distribution::is_variation(doc),
            doc.root_element()
                .children()
                .find(|c| c.has_tag_name("Catalog"))
                .map(|c| catalog_template(&c)),
        ),
        Err(_) => return,
    };
    if is_variation {
        if let Ok(v) = paracosm_openscenario::distribution::read_variation(&text) {
            for p in &v.params {
                let _ = p.dist.levels();
            }
        }
        let _ = variation_of_template(s);
    } else if let Some(template) = catalog {
        let _ = catalog_through(s, &template);
    } else {
        let _ = paracosm_openscenario::read_scenario_text(&text, std::path::Path::new(""), &[]);
    }
}

/// The scenario the `openscenario` fuzz target reads a fuzzed variation file with: three
/// declared parameters (a double, an int, a string) that its storyboard reads and one
/// vehicle. No map: nothing is simulated.
pub const FUZZ_TEMPLATE: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="1" date="2026-11-29T00:00:00" description="fuzz template" author="paracosm"/>
  <ParameterDeclarations>
    <ParameterDeclaration name="Speed" parameterType="double" value="10"/>
    <ParameterDeclaration name="Lane" parameterType="int" value="-1"/>
    <ParameterDeclaration name="Label" parameterType="string" value="a"/>
  </ParameterDeclarations>
  <Entities>
    <ScenarioObject name="Ego"><Vehicle name="v" vehicleCategory="car"><BoundingBox><Center x="1.4" y="0" z="0.8"/><Dimensions width="1.9" length="4.6" height="1.5"/></BoundingBox><Performance maxSpeed="50" maxAcceleration="5" maxDeceleration="9"/><Axles><FrontAxle maxSteering="0.5" wheelDiameter="0.6" trackWidth="1.6" positionX="2.8" positionZ="0.3"/><RearAxle maxSteering="0" wheelDiameter="0.6" trackWidth="1.6" positionX="0" positionZ="0.3"/></Axles><Properties/></Vehicle></ScenarioObject>
  </Entities>
  <Storyboard>
    <Init><Actions>
      <Private entityRef="Ego">
        <PrivateAction><TeleportAction><Position><WorldPosition x="0" y="${$Lane * 3.5}"/></Position></TeleportAction></PrivateAction>
        <PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="$Speed"/></SpeedActionTarget></SpeedAction></LongitudinalAction></PrivateAction>
      </Private>
    </Actions></Init>
    <StopTrigger><ConditionGroup><Condition name="end" delay="0" conditionEdge="none"><ByValueCondition><ParameterCondition parameterRef="Label" value="b" rule="equalTo"/></ByValueCondition></Condition></ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"#;

/// XML text with `&`, `<`, `>` and `"` escaped, for an attribute value.
fn escaped(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A scenario that reads the entries of the catalog element `catalog` from the folder
/// `catalogs`: one entity per vehicle, pedestrian and object entry (the first 8), the first
/// entity's controller the first controller entry, each placed at the origin. No map.
pub fn catalog_template(catalog: &roxmltree::Node<'_, '_>) -> String {
    let name = escaped(catalog.attribute("name").unwrap_or(""));
    let entries = |kinds: &[&str]| -> Vec<String> {
        catalog
            .children()
            .filter(|c| kinds.iter().any(|k| c.has_tag_name(*k)))
            .filter_map(|c| c.attribute("name").map(escaped))
            .collect()
    };
    let objects = entries(&["Vehicle", "Pedestrian", "MiscObject"]);
    let controller = entries(&["Controller"]).into_iter().next();
    let mut entities = String::new();
    let mut init = String::new();
    for (i, entry) in objects.iter().take(8).enumerate() {
        let control = match (&controller, i) {
            (Some(c), 0) => format!(
                r#"<ObjectController><CatalogReference catalogName="{name}" entryName="{c}"/></ObjectController>"#
            ),
            _ => String::new(),
        };
        entities.push_str(&format!(
            r#"<ScenarioObject name="E{i}"><CatalogReference catalogName="{name}" entryName="{entry}"/>{control}</ScenarioObject>"#
        ));
        init.push_str(&format!(
            r#"<Private entityRef="E{i}"><PrivateAction><TeleportAction><Position><WorldPosition x="{x}" y="0"/></Position></TeleportAction></PrivateAction></Private>"#,
            x = 10 * i
        ));
    }
    let folders = ["Vehicle", "Pedestrian", "MiscObject", "Controller"]
        .map(|k| format!(r#"<{k}Catalog><Directory path="catalogs"/></{k}Catalog>"#))
        .concat();
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="1" date="2026-11-29T00:00:00" description="reads a catalog" author="paracosm"/>
  <CatalogLocations>{folders}</CatalogLocations>
  <Entities>{entities}</Entities>
  <Storyboard><Init><Actions>{init}</Actions></Init>
    <StopTrigger><ConditionGroup><Condition name="end" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="1" rule="greaterThan"/></ByValueCondition></Condition></ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"#
    )
}

/// A folder of its own for this process and thread, under the system's temporary folder,
/// holding [`FUZZ_TEMPLATE`] as `template.xosc` and a `catalogs` folder (its one file
/// rewritten for each catalog).
fn fuzz_folder() -> std::io::Result<std::path::PathBuf> {
    let dir = std::env::temp_dir().join(format!(
        "paracosm-fuzz-{}-{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::create_dir_all(dir.join("catalogs"))?;
    std::fs::write(dir.join("template.xosc"), FUZZ_TEMPLATE)?;
    Ok(dir)
}

/// Reads the catalog file `catalog` (saved as `catalogs/fuzz.xosc`) through the scenario
/// `template` ([`catalog_template`]): the scenario read, or why not.
///
/// # Errors
/// [`FuzzReadError`]: the reader's error, or the folder's that could not be written.
pub fn catalog_through(
    catalog: &str,
    template: &str,
) -> Result<paracosm_openscenario::model::Scenario, FuzzReadError> {
    let dir = fuzz_folder()?;
    let path = dir.join("catalog_template.xosc");
    std::fs::write(dir.join("catalogs/fuzz.xosc"), catalog)?;
    std::fs::write(&path, template)?;
    Ok(paracosm_openscenario::read_scenario(&path, &[])?)
}

/// Why a fuzzed catalog or variation file did not read ([`catalog_through`],
/// [`variation_of_template`]).
#[derive(Debug, thiserror::Error)]
pub enum FuzzReadError {
    /// The fuzz folder or a file in it could not be written.
    #[error("the fuzz folder: {0}")]
    Folder(#[from] std::io::Error),
    /// The OpenSCENARIO reader refused the file.
    #[error(transparent)]
    Xosc(#[from] paracosm_openscenario::XoscError),
    /// The OpenSCENARIO front end refused the variation.
    #[error(transparent)]
    Scenario(#[from] paracosm_scenarios::ScenarioError),
}

/// Reads `variation` as a variation file beside [`FUZZ_TEMPLATE`] (which its `ScenarioFile`
/// may name as `template.xosc`), as `paracosm-fuzz xosc` inspects one: the number of
/// parameters of its space, or why it does not read.
///
/// # Errors
/// [`FuzzReadError`]: the front end's error, or the folder's that could not be written.
pub fn variation_of_template(variation: &str) -> Result<usize, FuzzReadError> {
    let dir = fuzz_folder()?;
    let path = dir.join("variation.xosc");
    std::fs::write(&path, variation)?;
    Ok(paracosm_scenarios::xosc::inspect(&path, &[], false)?
        .space
        .len())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seed(name: &str) -> String {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fuzz/regressions/openscenario")
            .join(name);
        std::fs::read_to_string(path).unwrap()
    }

    /// The catalog `text` read through the scenario made from its own entries.
    fn read_catalog(text: &str) -> Result<paracosm_openscenario::model::Scenario, FuzzReadError> {
        let t = paracosm_openscenario::Text::new("c.xosc", text.to_owned());
        let doc = t.parse().unwrap();
        let c = doc
            .root_element()
            .children()
            .find(|c| c.has_tag_name("Catalog"));
        catalog_through(text, &catalog_template(&c.unwrap()))
    }

    #[test]
    fn a_catalog_is_read_through_a_scenario_of_its_own_entries() {
        let s = read_catalog(&seed("catalog_entries.xosc")).unwrap();
        assert_eq!(s.entities.len(), 2);
        assert_eq!(s.entities[0].dimensions_m[0], 4.6);
        assert!(!s.entities[0].controllers.is_empty());
        // A broken entry fails the read, so the fuzzer's mutations reach the entry readers.
        let broken = seed("catalog_entries.xosc").replace("value=\"4.6\"", "value=\"x\"");
        assert!(read_catalog(&broken).is_err());
        // The shipped catalogs, whatever their entries' names, read.
        let alks = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/xosc/alks/concrete_scenarios/catalogs");
        for kind in ["vehicles", "pedestrians", "misc_objects"] {
            for f in std::fs::read_dir(alks.join(kind)).unwrap() {
                let text = std::fs::read_to_string(f.unwrap().path()).unwrap();
                let s = read_catalog(&text).unwrap();
                assert!(!s.entities.is_empty(), "{kind}");
            }
        }
    }

    #[test]
    fn the_variation_seed_varies_the_templates_parameters() {
        assert_eq!(
            variation_of_template(&seed("variation_of_template.xosc")).unwrap(),
            3
        );
        let undeclared = seed("variation_of_template.xosc").replace("\"Lane\"", "\"Lanes\"");
        let e = variation_of_template(&undeclared).unwrap_err().to_string();
        assert!(e.contains("\"Lanes\" is varied but"), "{e}");
    }
}
