//! URDF loader (visuals, collisions and meshes are ignored).
//!
//! * `<visual>`, `<collision>` and `<material>` elements are removed before parsing, so
//!   their content (meshes, textures...) can neither be required nor make a file fail to
//!   load (e.g. iCub's `<texture/>` without a file name, which urdfdom accepts).
//! * Revolute, continuous and prismatic joints become model joints (a continuous joint is
//!   a revolute joint with one angle and no position limits); fixed joints merge their
//!   child link's inertia into the parent body and add a `fixed_joint` frame.
//! * A revolute or prismatic joint must have a `<limit>` element (urdfdom refuses it
//!   too); the error names the joint. A velocity or effort limit ≤ 0 means none.
//! * Every link gets a `body` frame and every moving joint a `joint` frame; frame 0 is
//!   `universe`. With a planar or free-flyer root, the root joint is named `root_joint`
//!   ([`ROOT_JOINT_NAME`]; a URDF joint of that name is then an error).
//! * A link without `<inertial>` is massless. A present inertial must have a finite mass
//!   ≥ 0 and a positive (semi-)definite rotational inertia: an eigenvalue below
//!   −[`INERTIA_TOLERANCE`] is an error; zero eigenvalues are accepted (point masses and
//!   thin rods exist in real robot descriptions, e.g. TIAGo's tool links, and Pinocchio
//!   loads them). The small negative tolerance exists because published files round
//!   tiny inertias badly: TIAGo's two antenna links weigh 1 mg and their printed
//!   inertia tensors have an eigenvalue of −3.5·10⁻⁸ kg·m².
//! * What the algorithms use is the merged body of each joint (all links rigidly attached
//!   to it); [`ModelBuilder::build`] checks every merged body positive semidefinite (to
//!   round-off), so the joint-space inertia matrix stays positive definite. TIAGo's
//!   antennas merge into its 28 kg base and pass; a slightly indefinite link that forms a
//!   body of its own is refused, naming the joint.
//! * `floating`, `planar` and `spherical` joints inside the URDF are rejected with a clear
//!   error (choose the robot's base with [`RootJoint`] instead).
//! * Mimic joints are loaded as independent joints (the `<mimic>` tag is ignored).
//! * With a fixed root, the root link's inertia belongs to the world and takes no part in
//!   the dynamics, the total mass or the CoM (as Pinocchio).

use crate::multibody::{
    FrameIndex, FrameKind, JointIndex, JointLimits, JointType, Model, ModelBuilder, RootJoint,
};
use crate::spatial::{Inertia, SE3};
use crate::{Error, Result};
use nalgebra::{Matrix3, Vector3};
use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// Loads a robot model from a URDF file with the given root joint.
///
/// # Errors
/// [`Error::Io`] if the file cannot be read, [`Error::Parse`] (naming the file and the
/// element) for malformed XML, cycles, unknown links, bad inertials, unsupported joints.
pub fn model_from_urdf_file(path: impl AsRef<Path>, root: RootJoint) -> Result<Model> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    model_from_urdf_str(&text, root, &path.display().to_string())
}

fn pose(p: &urdf_rs::Pose) -> SE3 {
    SE3::from_xyz_rpy(p.xyz.0, p.rpy.0)
}

fn finite_pose(p: &urdf_rs::Pose) -> bool {
    p.xyz.0.iter().chain(p.rpy.0.iter()).all(|x| x.is_finite())
}

/// Name of the planar or free-flyer root joint (as Pinocchio's default); a URDF joint of
/// that name is an error with those roots.
pub const ROOT_JOINT_NAME: &str = "root_joint";

/// Most negative eigenvalue (kg·m²) tolerated in one link's rotational inertia: round-off
/// in published URDFs (TIAGo's 1 mg antenna links have eigenvalues of −3.5e-8 kg·m², from
/// tensors printed with four significant digits). The merged body that the link becomes
/// part of must still be positive semidefinite ([`ModelBuilder::build`]).
pub const INERTIA_TOLERANCE: f64 = 1e-6;

/// Validates a link's inertial; `None` for a massless link.
fn link_inertia(link: &urdf_rs::Link, src: &str) -> Result<Option<(Inertia, SE3)>> {
    let inl = &link.inertial;
    let m = inl.mass.value;
    let i = &inl.inertia;
    let vals = [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz];
    let err = |msg: String| Error::parse(src, format!("link '{}' inertial: {msg}", link.name));
    if !m.is_finite() {
        return Err(err(format!("mass is not finite ({m})")));
    }
    if m < 0.0 {
        return Err(err(format!("mass must be >= 0, got {m}")));
    }
    if vals.iter().any(|x| !x.is_finite()) {
        return Err(err("inertia has a non-finite entry".into()));
    }
    if !finite_pose(&inl.origin) {
        return Err(err("origin has a non-finite entry".into()));
    }
    let ic = Matrix3::new(
        i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
    );
    if m == 0.0 && vals.iter().all(|x| *x == 0.0) {
        return Ok(None);
    }
    let e = ic.symmetric_eigenvalues();
    if e.min() < -INERTIA_TOLERANCE {
        return Err(err(format!(
            "inertia matrix is not positive definite (eigenvalues {:.3e}, {:.3e}, {:.3e} kg·m²; \
             only round-off down to -{INERTIA_TOLERANCE:e} is tolerated)",
            e[0], e[1], e[2]
        )));
    }
    Ok(Some((
        Inertia::new(m, Vector3::zeros(), ic),
        pose(&inl.origin),
    )))
}

/// Loads a robot model from URDF text; `source_name` names the input in error messages.
///
/// The steps: strip the ignored elements and parse ([`parse_robot`]); index the links and
/// joints into a tree ([`UrdfTree::new`]); add the root joint; walk the tree depth-first,
/// adding one model joint per moving URDF joint and merging fixed joints
/// ([`TreeWalk`]); build and validate the model.
///
/// # Errors
/// As [`model_from_urdf_file`].
pub fn model_from_urdf_str(text: &str, root: RootJoint, source_name: &str) -> Result<Model> {
    let src = source_name;
    let text = strip_ignored_elements(text);
    let robot = parse_robot(&text, src)?;
    let tree = UrdfTree::new(&robot, &text, src)?;
    let mut b = ModelBuilder::new(robot.name.clone());
    b.set_root(root);
    let (root_joint, root_frame) = add_root_joint(&mut b, root, &tree)?;
    let mut walk = TreeWalk {
        tree: &tree,
        b,
        visited: vec![false; robot.links.len()],
        stack: Vec::new(),
    };
    walk.visit_link(tree.root_link, root_joint, SE3::identity(), root_frame)?;
    while let Some(entry) = walk.stack.pop() {
        walk.add_urdf_joint(entry)?;
    }
    if let Some(l) = walk.visited.iter().position(|v| !v) {
        return Err(Error::parse(
            src,
            format!(
                "link '{}' is not connected to the root link '{}' (cyclic or disconnected kinematic graph)",
                robot.links[l].name, robot.links[tree.root_link].name
            ),
        ));
    }
    walk.b.build().map_err(|e| in_source(src, e))
}

/// Parses the (stripped) URDF text, naming the first refused link or joint.
fn parse_robot(text: &str, src: &str) -> Result<urdf_rs::Robot> {
    let robot = urdf_rs::read_from_string(text).map_err(|e| {
        let msg = match locate_parse_error(text) {
            Some((kind, name, err)) => format!("{kind} '{name}': {err}"),
            None => e.to_string(),
        };
        Error::parse(src, format!("malformed URDF: {msg}"))
    })?;
    if robot.links.is_empty() {
        return Err(Error::parse(src, "the robot has no <link>"));
    }
    Ok(robot)
}

/// Builder errors rephrased as parse errors of the source `src`.
fn in_source(src: &str, e: Error) -> Error {
    match e {
        Error::InvalidInput { field, message } => Error::parse(src, format!("{field}: {message}")),
        Error::NonFinite { field } => Error::parse(src, format!("{field}: non-finite value")),
        Error::WrongLength {
            field,
            expected,
            got,
        } => Error::parse(
            src,
            format!("{field}: expected {expected} values, got {got}"),
        ),
        other => other,
    }
}

/// The URDF's links and joints indexed as a tree, checked for unique names, existing
/// links, one parent per link and a single root link.
struct UrdfTree<'a> {
    robot: &'a urdf_rs::Robot,
    src: &'a str,
    link_ix: HashMap<&'a str, usize>,
    /// Child joints of each link, in urdfdom's visiting order (byte order of names).
    children: Vec<Vec<usize>>,
    /// Names of the top-level joints that have a `<limit>` element.
    limited: HashSet<String>,
    joint_names: HashSet<&'a str>,
    root_link: usize,
}

impl<'a> UrdfTree<'a> {
    fn new(robot: &'a urdf_rs::Robot, text: &str, src: &'a str) -> Result<Self> {
        let link_ix = index_links(robot, src)?;
        let mut joint_names: HashSet<&str> = HashSet::new();
        let mut parent_joint_of: Vec<Option<usize>> = vec![None; robot.links.len()];
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
        for (k, j) in robot.joints.iter().enumerate() {
            if j.name.is_empty() {
                return Err(Error::parse(src, format!("joint #{k} has no name")));
            }
            if !joint_names.insert(&j.name) {
                return Err(Error::parse(
                    src,
                    format!("duplicate joint name '{}'", j.name),
                ));
            }
            let link = |role: &str, name: &str| {
                link_ix.get(name).copied().ok_or_else(|| {
                    Error::parse(
                        src,
                        format!("joint '{}': {role} link '{name}' does not exist", j.name),
                    )
                })
            };
            let p = link("parent", &j.parent.link)?;
            let c = link("child", &j.child.link)?;
            if let Some(other) = parent_joint_of[c] {
                return Err(Error::parse(
                    src,
                    format!(
                        "link '{}' is the child of two joints ('{}' and '{}'): not a tree",
                        j.child.link, robot.joints[other].name, j.name
                    ),
                ));
            }
            parent_joint_of[c] = Some(k);
            children[p].push(k);
        }
        // Children in the order Pinocchio (urdfdom) visits them: sorted by joint name.
        // This makes the joint order, hence the layout of q and v, identical to
        // Pinocchio's.
        for c in &mut children {
            c.sort_by(|&x, &y| robot.joints[x].name.cmp(&robot.joints[y].name));
        }
        let root_link = single_root_link(robot, &parent_joint_of, src)?;
        Ok(Self {
            robot,
            src,
            link_ix,
            children,
            limited: joints_with_limit(text),
            joint_names,
            root_link,
        })
    }
}

/// Link name → index, refusing unnamed and duplicate links.
fn index_links<'a>(robot: &'a urdf_rs::Robot, src: &str) -> Result<HashMap<&'a str, usize>> {
    let mut link_ix = HashMap::new();
    for (k, l) in robot.links.iter().enumerate() {
        if l.name.is_empty() {
            return Err(Error::parse(src, format!("link #{k} has no name")));
        }
        if link_ix.insert(l.name.as_str(), k).is_some() {
            return Err(Error::parse(
                src,
                format!("duplicate link name '{}'", l.name),
            ));
        }
    }
    Ok(link_ix)
}

/// The one link without a parent joint.
fn single_root_link(
    robot: &urdf_rs::Robot,
    parent_joint_of: &[Option<usize>],
    src: &str,
) -> Result<usize> {
    let roots: Vec<usize> = (0..robot.links.len())
        .filter(|&l| parent_joint_of[l].is_none())
        .collect();
    match roots.as_slice() {
        [r] => Ok(*r),
        [] => Err(Error::parse(
            src,
            "the kinematic graph is cyclic: every link has a parent joint",
        )),
        many => {
            let names: Vec<&str> = many.iter().map(|&l| robot.links[l].name.as_str()).collect();
            Err(Error::parse(
                src,
                format!(
                    "several root links (links without a parent joint): {}",
                    names.join(", ")
                ),
            ))
        }
    }
}

/// Adds the planar or free-flyer root joint (none for a fixed root); returns the joint
/// that carries the root link and the frame it hangs from.
fn add_root_joint(
    b: &mut ModelBuilder,
    root: RootJoint,
    tree: &UrdfTree<'_>,
) -> Result<(JointIndex, FrameIndex)> {
    let jt = match root {
        RootJoint::Fixed => return Ok((JointIndex(0), FrameIndex(0))),
        RootJoint::Planar => JointType::Planar,
        RootJoint::FreeFlyer => JointType::FreeFlyer,
    };
    if tree.joint_names.contains(ROOT_JOINT_NAME) {
        return Err(Error::parse(
            tree.src,
            format!(
                "joint '{ROOT_JOINT_NAME}': this name is reserved for the {root} root joint \
                 (rename the URDF joint, or use the fixed root)"
            ),
        ));
    }
    let j = b
        .add_joint(
            JointIndex(0),
            ROOT_JOINT_NAME,
            jt,
            SE3::identity(),
            JointLimits::unlimited(),
        )
        .map_err(|e| in_source(tree.src, e))?;
    Ok((j, FrameIndex(b.nframes() - 1)))
}

/// A URDF joint waiting to be added: its index, the model joint carrying its parent link,
/// `joint_from_parent_link` and the parent link's body frame.
type Pending = (usize, JointIndex, SE3, FrameIndex);

/// The depth-first walk over the URDF tree that fills the model builder (a recursive
/// descent in document order, with an explicit stack).
struct TreeWalk<'t, 'a> {
    tree: &'t UrdfTree<'a>,
    b: ModelBuilder,
    visited: Vec<bool>,
    stack: Vec<Pending>,
}

impl TreeWalk<'_, '_> {
    /// Adds link `l` (its body frame and inertia) to model joint `joint` and queues its
    /// child joints.
    fn visit_link(
        &mut self,
        l: usize,
        joint: JointIndex,
        joint_from_link: SE3,
        parent_frame: FrameIndex,
    ) -> Result<()> {
        let src = self.tree.src;
        self.visited[l] = true;
        let link = &self.tree.robot.links[l];
        let body_frame = self
            .b
            .add_frame(
                &link.name,
                joint,
                parent_frame,
                joint_from_link,
                FrameKind::Body,
            )
            .map_err(|e| in_source(src, e))?;
        if let Some((inertia, origin)) = link_inertia(link, src)? {
            self.b
                .append_body_inertia(joint, &inertia, &joint_from_link.compose(&origin))
                .map_err(|e| in_source(src, e))?;
        }
        for &jk in self.tree.children[l].iter().rev() {
            self.stack.push((jk, joint, joint_from_link, body_frame));
        }
        Ok(())
    }

    /// Adds URDF joint `jk`: a frame for a fixed joint (its child merges into the same
    /// body), a model joint for a moving one; then visits its child link.
    fn add_urdf_joint(&mut self, (jk, joint, joint_from_link, body_frame): Pending) -> Result<()> {
        let src = self.tree.src;
        let uj = &self.tree.robot.joints[jk];
        if !finite_pose(&uj.origin) {
            return Err(Error::parse(
                src,
                format!("joint '{}' origin: non-finite value", uj.name),
            ));
        }
        let placement = joint_from_link.compose(&pose(&uj.origin));
        let child = self.tree.link_ix[uj.child.link.as_str()];
        if uj.joint_type == urdf_rs::JointType::Fixed {
            let f = self
                .b
                .add_frame(
                    &uj.name,
                    joint,
                    body_frame,
                    placement,
                    FrameKind::FixedJoint,
                )
                .map_err(|e| in_source(src, e))?;
            return self.visit_link(child, joint, placement, f);
        }
        let (jt, limits) = moving_joint(uj, self.tree.limited.contains(&uj.name), src)?;
        let j = self
            .b
            .add_joint(joint, &uj.name, jt, placement, limits)
            .map_err(|e| in_source(src, e))?;
        let jf = FrameIndex(self.b.nframes() - 1);
        self.visit_link(child, j, SE3::identity(), jf)
    }
}

/// The model joint type and limits of a moving URDF joint. A revolute or prismatic joint
/// needs a `<limit>` element (`has_limit`), as urdfdom requires; a continuous one has no
/// position limits. A velocity or effort limit ≤ 0 means none.
fn moving_joint(
    uj: &urdf_rs::Joint,
    has_limit: bool,
    src: &str,
) -> Result<(JointType, JointLimits)> {
    use urdf_rs::JointType as U;
    let err_axis = |e: Error| match e {
        Error::InvalidInput { message, .. } => {
            Error::parse(src, format!("joint '{}' axis: {message}", uj.name))
        }
        other => other,
    };
    let axis = Vector3::from(uj.axis.xyz.0);
    let jt = match uj.joint_type {
        U::Prismatic => JointType::prismatic(axis).map_err(err_axis)?,
        U::Revolute | U::Continuous => JointType::revolute(axis).map_err(err_axis)?,
        ref other => {
            let kind = match other {
                U::Floating => "floating",
                U::Planar => "planar",
                _ => "spherical",
            };
            return Err(Error::parse(
                src,
                format!(
                    "joint '{}': unsupported joint type '{kind}' (supported: revolute, \
                     continuous, prismatic, fixed; choose a planar or free-flyer base with \
                     the root option instead)",
                    uj.name
                ),
            ));
        }
    };
    let continuous = uj.joint_type == U::Continuous;
    if !continuous && !has_limit {
        let kind = if jt.is_prismatic() {
            "prismatic"
        } else {
            "revolute"
        };
        return Err(Error::parse(
            src,
            format!(
                "joint '{}': a {kind} joint needs a <limit> element (lower, upper, effort, \
                 velocity), as urdfdom requires; use type=\"continuous\" for an unbounded \
                 revolute joint",
                uj.name
            ),
        ));
    }
    let limit = &uj.limit;
    let positive_or_inf = |x: f64| if x > 0.0 { x } else { f64::INFINITY };
    let (vel, eff) = (
        positive_or_inf(limit.velocity),
        positive_or_inf(limit.effort),
    );
    let limits = if continuous {
        JointLimits::scalar(f64::NEG_INFINITY, f64::INFINITY, vel, eff)
    } else {
        JointLimits::scalar(limit.lower, limit.upper, vel, eff)
    };
    Ok((jt, limits))
}

/// Names of the joints (children of `<robot>`) that contain a `<limit>` element. The
/// parser cannot tell: it reads a missing `<limit>` as all zeros.
fn joints_with_limit(text: &str) -> HashSet<String> {
    let mut out = HashSet::new();
    let mut pos = 0;
    let mut depth = 0usize;
    let mut joint: Option<String> = None; // the open top-level joint
    while let Some((start, end, tag)) = next_tag(text, pos) {
        pos = end;
        match tag {
            Tag::Start(n) => {
                if depth == 1 && n == "joint" {
                    joint = attribute(&text[start..end], "name").map(str::to_string);
                } else if depth == 2 && n == "limit" {
                    out.extend(joint.clone());
                }
                depth += 1;
            }
            Tag::Empty(n) if depth == 2 && n == "limit" => out.extend(joint.clone()),
            Tag::End => {
                depth = depth.saturating_sub(1);
                if depth == 1 {
                    joint = None;
                }
            }
            _ => {}
        }
    }
    out
}

/// Elements the loader ignores and removes before parsing.
const IGNORED_ELEMENTS: [&str; 3] = ["visual", "collision", "material"];

/// What [`next_tag`] found.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Tag<'a> {
    /// `<name ...>`.
    Start(&'a str),
    /// `</name>`.
    End,
    /// `<name .../>`.
    Empty(&'a str),
    /// A comment, CDATA section, processing instruction or declaration.
    Other,
}

/// The first tag at or after byte `from`: (its first byte, one past its last byte, kind).
/// `None` at the end of the text or for an unterminated construct.
fn next_tag(text: &str, from: usize) -> Option<(usize, usize, Tag<'_>)> {
    let start = from + text.get(from..)?.find('<')?;
    let rest = &text[start..];
    let until = |pat: &str, skip: usize| rest.find(pat).map(|k| start + k + skip);
    if rest.starts_with("<!--") {
        return until("-->", 3).map(|e| (start, e, Tag::Other));
    }
    if rest.starts_with("<![CDATA[") {
        return until("]]>", 3).map(|e| (start, e, Tag::Other));
    }
    if rest.starts_with("<?") {
        return until("?>", 2).map(|e| (start, e, Tag::Other));
    }
    // the end of a start/end tag or declaration: the first '>' outside quotes
    let mut quote = None;
    let mut end = None;
    for (k, c) in rest.char_indices().skip(1) {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '>') => {
                end = Some(start + k + 1);
                break;
            }
            _ => {}
        }
    }
    let end = end?;
    if rest.starts_with("<!") {
        return Some((start, end, Tag::Other));
    }
    if rest.starts_with("</") {
        return Some((start, end, Tag::End));
    }
    let name_len = rest[1..]
        .find(|c: char| c.is_whitespace() || c == '/' || c == '>')
        .unwrap_or(0);
    let name = &rest[1..1 + name_len];
    if text[..end - 1].ends_with('/') {
        Some((start, end, Tag::Empty(name)))
    } else {
        Some((start, end, Tag::Start(name)))
    }
}

/// `text` without its [`IGNORED_ELEMENTS`] (and their content). Malformed XML is
/// returned as far as it could be scanned, for the parser to report.
fn strip_ignored_elements(text: &str) -> Cow<'_, str> {
    let mut out = String::new();
    let mut copied = 0; // text[..copied] is in `out` (or dropped)
    let mut pos = 0;
    // (start of the ignored element, depth of open elements inside it)
    let mut skipping: Option<(usize, usize)> = None;
    while let Some((start, end, tag)) = next_tag(text, pos) {
        pos = end;
        match (skipping, tag) {
            (None, Tag::Start(name)) if IGNORED_ELEMENTS.contains(&name) => {
                skipping = Some((start, 1));
            }
            (None, Tag::Empty(name)) if IGNORED_ELEMENTS.contains(&name) => {
                out.push_str(&text[copied..start]);
                copied = end;
            }
            (Some((s, d)), Tag::Start(_)) => skipping = Some((s, d + 1)),
            (Some((s, 1)), Tag::End) => {
                out.push_str(&text[copied..s]);
                copied = end;
                skipping = None;
            }
            (Some((s, d)), Tag::End) => skipping = Some((s, d - 1)),
            _ => {}
        }
    }
    if copied == 0 {
        return Cow::Borrowed(text);
    }
    out.push_str(&text[copied..]);
    Cow::Owned(out)
}

/// The value of attribute `name` in a start tag.
fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let mut rest = tag;
    while let Some(k) = rest.find(name) {
        let before_ok = rest[..k].ends_with(char::is_whitespace);
        let after = rest[k + name.len()..].trim_start();
        if before_ok && let Some(v) = after.strip_prefix('=') {
            let v = v.trim_start();
            let q = v.chars().next()?;
            if q == '"' || q == '\'' {
                return v[1..].find(q).map(|e| &v[1..1 + e]);
            }
        }
        rest = &rest[k + name.len()..];
    }
    None
}

/// When the parser refuses a file, the first `<link>` or `<joint>` (a child of `<robot>`)
/// that it refuses on its own: (element, its name, the parser's message).
fn locate_parse_error(text: &str) -> Option<(&'static str, String, String)> {
    let mut pos = 0;
    let mut depth = 0usize;
    let mut open: Option<(usize, &str)> = None; // start of the current robot child
    let mut version = String::new(); // the URDF version changes how limits are read
    while let Some((start, end, tag)) = next_tag(text, pos) {
        pos = end;
        let element = match tag {
            Tag::Start(n) => {
                if depth == 0
                    && let Some(v) = attribute(&text[start..end], "version")
                {
                    version = format!(" version=\"{v}\"");
                }
                depth += 1;
                if depth == 2 {
                    open = Some((start, n));
                }
                None
            }
            Tag::End => {
                depth = depth.saturating_sub(1);
                if depth == 1 {
                    open.take().map(|(s, n)| (s, n, &text[s..end]))
                } else {
                    None
                }
            }
            Tag::Empty(n) if depth == 1 => Some((start, n, &text[start..end])),
            _ => None,
        };
        let Some((s, kind, body)) = element else {
            continue;
        };
        let kind = match kind {
            "link" => "link",
            "joint" => "joint",
            _ => continue,
        };
        let probe = format!("<robot name=\"probe\"{version}>{body}</robot>");
        if let Err(e) = urdf_rs::read_from_string(&probe) {
            let start_tag = &text[s..next_tag(text, s).map_or(s, |t| t.1)];
            let name = attribute(start_tag, "name").unwrap_or("?").to_string();
            return Some((kind, name, e.to_string()));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::{attribute, locate_parse_error, strip_ignored_elements};

    #[test]
    fn parse_errors_name_the_element() {
        let text = r#"<robot name="r"><link name="a"/>
            <joint name='j1' type="revolute"><parent link="a"/><child link="b"/>
              <limit lower="0" upper="1" effort="1" velocity="1"/></joint>
            <link name="b"><inertial><mass value="1"/></inertial></link>
            <joint name="j2" type="revolute"><parent link="b"/><child link="c"/>
              <limit lower="0" upper="1" effort="1"/></joint></robot>"#;
        let (kind, name, err) = locate_parse_error(text).unwrap();
        assert_eq!((kind, name.as_str()), ("link", "b"));
        assert!(err.contains("inertia"), "{err}");
        let fixed = text.replace(
            "<mass value=\"1\"/>",
            "<mass value=\"1\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/>",
        );
        let (kind, name, err) = locate_parse_error(&fixed).unwrap();
        assert_eq!((kind, name.as_str()), ("joint", "j2"));
        assert!(err.contains("velocity"), "{err}");
        assert_eq!(
            attribute(r#"<joint type="x" name = 'n'>"#, "name"),
            Some("n")
        );
        assert_eq!(attribute(r#"<joint myname="x">"#, "name"), None);
    }

    #[test]
    fn strips_visuals_collisions_and_materials_only() {
        let text = r#"<?xml version="1.0"?><!-- <visual> in a comment stays -->
<robot name="r"><material name="m"><texture/></material>
<link name="a"><inertial><mass value="1"/></inertial>
  <visual name="x>y"><geometry><mesh/></geometry><material name="n"/></visual>
  <collision/><collision><geometry><box size="1 1 1"/></geometry></collision>
  <visualise/></link><![CDATA[<collision>]]></robot>"#;
        let got = strip_ignored_elements(text);
        assert_eq!(
            got,
            r#"<?xml version="1.0"?><!-- <visual> in a comment stays -->
<robot name="r">
<link name="a"><inertial><mass value="1"/></inertial>
  
  
  <visualise/></link><![CDATA[<collision>]]></robot>"#
        );
        // nothing to strip: the text itself
        let plain = r#"<robot name="r"><link name="a"/></robot>"#;
        assert!(matches!(
            strip_ignored_elements(plain),
            std::borrow::Cow::Borrowed(_)
        ));
        // unterminated: scanned as far as possible, the parser reports the rest
        let bad = r#"<robot name="r"><visual><geometry>"#;
        assert_eq!(strip_ignored_elements(bad), bad);
    }
}
