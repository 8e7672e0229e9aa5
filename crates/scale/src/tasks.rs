//! Block tasks as data, so that another process can run them: a round's
//! tasks are written to a JSON file in the round's folder (`tasks.json`),
//! which a worker (a Ray task through `pylodkit.blocks`, or anything that
//! links this crate) reads back to run task `i` with [`run_task`].
//!
//! The file names each block's input and output by file name only,
//! relative to the task file's folder: a worker on another machine that
//! mounts the shared folder elsewhere still finds them, and a task file
//! can never make a worker read or write outside its folder ([`read_tasks`]
//! refuses any name with a separator or `..`).

use std::path::{Path, PathBuf};

use lodkit_simplify::{AttributeWeights, Options};
use serde::{Deserialize, Serialize};

use crate::block::{BlockReport, Goal, simplify_block};
use crate::partition::{Cuts, Grid};
use crate::soup::Layout;
use glam::Vec3;

/// Version of the task file; [`read_tasks`] refuses any other, and any
/// field it does not know, so a worker with another lodkit never runs a
/// block by other rules than the driver's (2: each task names its goal;
/// 3: and the round's cuts, so a block locks only what may lie on one;
/// 4: the attribute weights as the simplifier's own `weights` object).
const TASKS_VERSION: u32 = 4;

/// Most tasks a task file may hold (a round has at most 512 blocks).
const MAX_TASKS: usize = 4096;

/// Largest task file [`read_tasks`] reads (4,096 tasks need under 1 MiB).
const MAX_TASK_FILE: u64 = 4 << 20;

/// One block to simplify: [`simplify_block`]'s arguments, as data.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockTask {
    /// The block's soup.
    pub input: PathBuf,
    /// Where its simplified soup goes (written atomically).
    pub output: PathBuf,
    /// How far the block goes.
    pub goal: Goal,
    /// The round's cuts: where the block's vertices may be shared.
    pub cuts: Cuts,
    /// Faces in the input (for progress).
    pub faces: u64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TaskFile {
    version: u32,
    options: OptionsRecord,
    /// The soups' attributes ([`Layout::tag`]).
    layout: String,
    tasks: Vec<TaskRecord>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TaskRecord {
    input: String,
    output: String,
    ratio: f64,
    /// `interior` or `total` ([`Goal`]).
    goal: String,
    cuts: CutsRecord,
    faces: u64,
}

/// [`Cuts`], its floats as written by `serde_json` (shortest form that
/// reads back the same bits).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CutsRecord {
    min: [f32; 3],
    cell: [f32; 3],
    g: u32,
    shift: f32,
    reach: f32,
}

impl CutsRecord {
    fn of(c: &Cuts) -> CutsRecord {
        CutsRecord {
            min: c.grid.min.to_array(),
            cell: c.grid.cell.to_array(),
            g: c.grid.g,
            shift: c.grid.shift,
            reach: c.reach,
        }
    }

    /// The cuts, or what is wrong with them: a grid of 1 to 64 blocks per
    /// axis, finite corner and shift, cells finite and positive (a NaN or
    /// negative reach is not refused: it locks every border vertex).
    fn cuts(&self) -> Result<Cuts, String> {
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        if !(1..=64).contains(&self.g)
            || !finite(&self.min)
            || !finite(&[self.shift])
            || !self.cell.iter().all(|&c| c.is_finite() && c > 0.0)
        {
            return Err(format!(
                "cuts {{ min {:?}, cell {:?}, g {}, shift {} }} are not a block grid",
                self.min, self.cell, self.g, self.shift
            ));
        }
        Ok(Cuts {
            grid: Grid {
                min: Vec3::from_array(self.min),
                cell: Vec3::from_array(self.cell),
                g: self.g,
                shift: self.shift,
            },
            reach: self.reach,
        })
    }
}

/// The options a block uses (its target is set per block, `lock_border`
/// and `fill_holes` by [`simplify_block`]).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct OptionsRecord {
    max_error: Option<f32>,
    heap_size: usize,
    weights: AttributeWeights,
    prune: Option<f32>,
    max_passes: u32,
}

impl OptionsRecord {
    fn of(o: &Options) -> OptionsRecord {
        OptionsRecord {
            max_error: o.max_error,
            heap_size: o.heap_size,
            weights: o.weights,
            prune: o.prune,
            max_passes: o.max_passes,
        }
    }

    fn options(&self) -> Options {
        Options {
            max_error: self.max_error,
            heap_size: self.heap_size,
            weights: self.weights,
            prune: self.prune,
            max_passes: self.max_passes,
            ..Options::default()
        }
    }
}

/// Writes `tasks` (all in the folder of `path`), the options `opts` and
/// the soups' `layout` to
/// the task file `path`, atomically. Errors: a task outside that folder,
/// I/O (messages name the file).
pub fn write_tasks(
    path: &Path,
    opts: &Options,
    layout: Layout,
    tasks: &[BlockTask],
) -> Result<(), String> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let name = |p: &Path| -> Result<String, String> {
        match (p.parent(), p.file_name().and_then(|n| n.to_str())) {
            (Some(d), Some(n)) if d == dir => Ok(n.to_string()),
            _ => Err(format!(
                "{}: block file {} is not in the task file's folder",
                path.display(),
                p.display()
            )),
        }
    };
    let file = TaskFile {
        version: TASKS_VERSION,
        options: OptionsRecord::of(opts),
        layout: layout.tag(),
        tasks: tasks
            .iter()
            .map(|t| {
                Ok(TaskRecord {
                    input: name(&t.input)?,
                    output: name(&t.output)?,
                    ratio: t.goal.ratio(),
                    goal: match t.goal {
                        Goal::Interior(_) => "interior",
                        Goal::Total(_) => "total",
                    }
                    .into(),
                    cuts: CutsRecord::of(&t.cuts),
                    faces: t.faces,
                })
            })
            .collect::<Result<_, String>>()?,
    };
    let json = serde_json::to_vec_pretty(&file).map_err(|e| format!("{}: {e}", path.display()))?;
    crate::soup::write_small(path, &json).map_err(|e| format!("{}: {e}", path.display()))
}

/// Reads the task file `path`: the options and the tasks, their paths
/// resolved in the file's folder. Errors (one line naming the file): I/O,
/// a file over 4 MiB, JSON that is not a task file of this version, more
/// than 4,096 tasks, a block name that is not a plain file name (a
/// separator, `..`, empty), a ratio outside [0, 1], cuts that are not a
/// block grid.
pub fn read_tasks(path: &Path) -> Result<(Options, Layout, Vec<BlockTask>), String> {
    let bad = |what: String| format!("{}: {what}", path.display());
    let len = std::fs::metadata(path)
        .map_err(|e| bad(e.to_string()))?
        .len();
    if len > MAX_TASK_FILE {
        return Err(bad(format!(
            "{len} bytes, over the {MAX_TASK_FILE} a task file may have"
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| bad(e.to_string()))?;
    let file: TaskFile =
        serde_json::from_slice(&bytes).map_err(|e| bad(format!("not a block task file: {e}")))?;
    if file.version != TASKS_VERSION {
        return Err(bad(format!(
            "task file version {}, this lodkit reads version {TASKS_VERSION}",
            file.version
        )));
    }
    if file.tasks.len() > MAX_TASKS {
        return Err(bad(format!(
            "{} tasks, at most {MAX_TASKS}",
            file.tasks.len()
        )));
    }
    let layout = Layout::from_tag(&file.layout)
        .ok_or_else(|| bad(format!("layout {:?}, expected -, or n, c, u", file.layout)))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let plain = |n: &str| -> Result<PathBuf, String> {
        let ok = !n.is_empty()
            && n != "."
            && n != ".."
            && !n.contains(['/', '\\', '\0'])
            && Path::new(n).file_name().is_some_and(|f| f == n);
        if ok {
            Ok(dir.join(n))
        } else {
            Err(bad(format!(
                "block file {n:?} is not a plain file name in the task file's folder"
            )))
        }
    };
    let tasks = file
        .tasks
        .iter()
        .map(|t| {
            if !(0.0..=1.0).contains(&t.ratio) {
                return Err(bad(format!("ratio {} outside [0, 1]", t.ratio)));
            }
            let goal = match t.goal.as_str() {
                "interior" => Goal::Interior(t.ratio),
                "total" => Goal::Total(t.ratio),
                g => return Err(bad(format!("goal {g:?}, expected interior or total"))),
            };
            Ok(BlockTask {
                input: plain(&t.input)?,
                output: plain(&t.output)?,
                goal,
                cuts: t.cuts.cuts().map_err(bad)?,
                faces: t.faces,
            })
        })
        .collect::<Result<_, String>>()?;
    Ok((file.options.options(), layout, tasks))
}

/// Runs task `index` of the task file `path` ([`read_tasks`], then
/// [`simplify_block`]): what a worker does. A task whose output already
/// exists whole ([`is_intact`](crate::soup::is_intact)) is not run again (its report reads the output's size). Errors:
/// those of [`read_tasks`] and [`simplify_block`], an index past the
/// tasks.
pub fn run_task(path: &Path, index: usize) -> Result<BlockReport, String> {
    let (opts, layout, tasks) = read_tasks(path)?;
    let t = tasks.get(index).ok_or_else(|| {
        format!(
            "{}: task {index}, the file has {}",
            path.display(),
            tasks.len()
        )
    })?;
    if crate::soup::is_intact(&t.output, layout) {
        let faces_out = crate::soup::faces_in(&t.output, layout)
            .map_err(|e| format!("{}: {e}", t.output.display()))?;
        return Ok(BlockReport {
            faces_in: t.faces,
            faces_out,
        });
    }
    let r = simplify_block(&t.input, &t.output, t.goal, &t.cuts, &opts, layout)?;
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_task_file_round_trips_and_refuses_names_outside_its_folder() {
        let d = tempfile::tempdir().unwrap();
        let path = d.path().join("tasks.json");
        let opts = Options {
            heap_size: 7,
            max_passes: 9,
            ..Options::default()
        };
        let tasks = vec![BlockTask {
            input: d.path().join("b00001.in"),
            output: d.path().join("b00001.out"),
            goal: Goal::Total(0.25),
            cuts: Cuts {
                grid: Grid::new(Vec3::new(-1.5, 0.1, 2.0), Vec3::new(0.3, 7.0, 2.5), 3, 0.5),
                reach: 0.1 + 0.2,
            },
            faces: 10,
        }];
        let layout = Layout {
            colors: true,
            ..Layout::default()
        };
        write_tasks(&path, &opts, layout, &tasks).unwrap();
        let (o, l, t) = read_tasks(&path).unwrap();
        assert_eq!(l, layout);
        assert_eq!(t, tasks);
        assert_eq!((o.heap_size, o.max_passes), (7, 9));
        assert_eq!(format!("{:?}", o.weights), format!("{:?}", opts.weights));

        let outside = vec![BlockTask {
            input: d.path().join("sub").join("x.in"),
            ..tasks[0].clone()
        }];
        assert!(write_tasks(&path, &opts, layout, &outside).is_err());
        for name in ["../x.in", "/etc/passwd", "..", "", "a/b"] {
            let json = format!(
                r#"{{"version":4,"options":{{"max_error":null,"heap_size":1,"weights":{{"normal":0,"color":0,"uv":0}},"prune":null,"max_passes":8}},"layout":"-","tasks":[{{"input":{name:?},"output":"o","ratio":0.5,"goal":"interior","cuts":{{"min":[0,0,0],"cell":[1,1,1],"g":2,"shift":0,"reach":0.5}},"faces":1}}]}}"#
            );
            std::fs::write(&path, json).unwrap();
            let e = read_tasks(&path).unwrap_err();
            assert!(e.contains("plain file name"), "{name}: {e}");
        }
        let json = r#"{"version":4,"options":{"max_error":null,"heap_size":1,"weights":{"normal":0,"color":0,"uv":0},"prune":null,"max_passes":8},"layout":"-","tasks":[{"input":"i","output":"o","ratio":0.5,"goal":"interior","cuts":{"min":[0,0,0],"cell":[1,1,1],"g":0,"shift":0,"reach":0.5},"faces":1}]}"#;
        std::fs::write(&path, json).unwrap();
        let e = read_tasks(&path).unwrap_err();
        assert!(e.contains("not a block grid"), "{e}");
        std::fs::write(&path, "{").unwrap();
        assert!(
            read_tasks(&path)
                .unwrap_err()
                .contains("not a block task file")
        );
    }
}
