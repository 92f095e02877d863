"""Generates the Pinocchio references of `tests/rigid_body_pinocchio_more.rs` with
Pinocchio 4.1.0 (Python bindings; `pip install pin==4.1.0`, which brings
example-robot-data 5.0.0).

Usage: python generate_more.py ROBOTS_DIR
where ROBOTS_DIR is example-robot-data's `robots` folder. Run from this folder.

1. Copies three robot descriptions of example-robot-data into `urdf/`, without their
   <visual> and <collision> elements (meshes are not shipped; the dynamics does not use
   them), with a provenance and license comment at the top (ElementTree drops the
   comments before <robot>; the license text is written in full instead):
     * anymal_c.urdf: a quadruped with unaligned joint axes
       (anymal_c_simple_description/urdf/anymal.urdf),
     * g1_29dof.urdf: a 29-joint humanoid (g1_description/urdf/g1_29dof_rev_1_0.urdf),
     * allegro_right_hand.urdf: a 16-joint hand, a wide tree on a fixed palm
       (allegro_hand_description/urdf/allegro_right_hand.urdf).
   `urdf/edge_general.urdf` (moma's synthetic edge cases, a copy of
   bench/xcheck_urdf/edge_general.urdf) is used as it is.
2. Loads each file in Pinocchio with the root of the case and writes NAME.json: the model
   metadata (joints, limits, frames, total mass) and, for a few seeded random states
   (q = neutral ⊕ U(−π, π)^nv; v, a, τ ~ U(−1, 1)), rnea, crba (symmetrised from the
   upper triangle), aba, nonLinearEffects, computeGeneralizedGravity,
   computeCoriolisMatrix (not for a planar root), centerOfMass, ccrba, kinetic and
   potential energy, the placement of every frame and the LOCAL_WORLD_ALIGNED Jacobian of
   a few frames. Conventions are Pinocchio's (see README.md).
"""
import json
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from pin_reference import joint_table, random_state

ERD_LICENSE = """example-robot-data is distributed under the BSD 3-Clause License:

Copyright (C) 2018-2020 LAAS-CNRS, University of Edinburgh, INRIA
Copyright note valid unless otherwise stated in individual files.
All rights reserved.

Redistribution and use in source and binary forms, with or without
modification, are permitted provided that the following conditions are met:

* Redistributions of source code must retain the above copyright notice, this
  list of conditions and the following disclaimer.

* Redistributions in binary form must reproduce the above copyright notice,
  this list of conditions and the following disclaimer in the documentation
  and/or other materials provided with the distribution.

* Neither the name of the copyright holder nor the names of its
  contributors may be used to endorse or promote products derived from
  this software without specific prior written permission.

THIS SOFTWARE IS PROVIDED BY THE COPYRIGHT HOLDERS AND CONTRIBUTORS "AS IS"
AND ANY EXPRESS OR IMPLIED WARRANTIES, INCLUDING, BUT NOT LIMITED TO, THE
IMPLIED WARRANTIES OF MERCHANTABILITY AND FITNESS FOR A PARTICULAR PURPOSE ARE
DISCLAIMED. IN NO EVENT SHALL THE COPYRIGHT HOLDER OR CONTRIBUTORS BE LIABLE
FOR ANY DIRECT, INDIRECT, INCIDENTAL, SPECIAL, EXEMPLARY, OR CONSEQUENTIAL
DAMAGES (INCLUDING, BUT NOT LIMITED TO, PROCUREMENT OF SUBSTITUTE GOODS OR
SERVICES; LOSS OF USE, DATA, OR PROFITS; OR BUSINESS INTERRUPTION) HOWEVER
CAUSED AND ON ANY THEORY OF LIABILITY, WHETHER IN CONTRACT, STRICT LIABILITY,
OR TORT (INCLUDING NEGLIGENCE OR OTHERWISE) ARISING IN ANY WAY OUT OF THE USE
OF THIS SOFTWARE, EVEN IF ADVISED OF THE POSSIBILITY OF SUCH DAMAGE."""

COPIES = [
    ("anymal_c.urdf", "anymal_c_simple_description/urdf/anymal.urdf",
     "anymal_c_simple_description/LICENSE"),
    ("g1_29dof.urdf", "g1_description/urdf/g1_29dof_rev_1_0.urdf", None),
    ("allegro_right_hand.urdf", "allegro_hand_description/urdf/allegro_right_hand.urdf", None),
]

# (output name, urdf, root, number of states)
CASES = [
    ("anymal_c_freeflyer", "anymal_c.urdf", "freeflyer", 3),
    ("g1_29dof_freeflyer", "g1_29dof.urdf", "freeflyer", 2),
    ("allegro_right_hand", "allegro_right_hand.urdf", "fixed", 3),
    ("edge_general_fixed", "edge_general.urdf", "fixed", 3),
    ("edge_general_planar", "edge_general.urdf", "planar", 3),
]

FRAME_TYPES = {
    pin.FrameType.JOINT: "joint",
    pin.FrameType.FIXED_JOINT: "fixed_joint",
    pin.FrameType.BODY: "body",
    pin.FrameType.OP_FRAME: "operational",
}


def strip_copy(robots, out, rel, license_file):
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    tree = ET.parse(robots + "/" + rel, parser)
    root = tree.getroot()
    for link in root.iter("link"):
        for child in list(link):
            if child.tag in ("visual", "collision"):
                link.remove(child)
    if license_file:
        with open(robots + "/" + license_file) as f:
            lic = "%s of example-robot-data 5.0.0:\n\n%s" % (license_file, f.read().strip())
    else:
        lic = ERD_LICENSE
    note = ET.Comment(
        "\nCopied from example-robot-data 5.0.0, robots/%s, by moma's\n"
        "tests/data/pinocchio/generate_more.py, which removed the <visual> and <collision>\n"
        "elements and the comments before <robot>, and re-indented the file; links, joints\n"
        "and inertials are unchanged.\n\n%s\n" % (rel, lic.replace("--", "- -")))
    root.insert(0, note)
    ET.indent(tree, space="  ")
    tree.write("urdf/" + out, encoding="unicode", xml_declaration=True)


def frame_pick(model):
    """The last BODY frame, the body of the middle joint and the last FIXED_JOINT frame."""
    bodies = [i for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY]
    out = [bodies[-1]]
    mid = [i for i in bodies if model.frames[i].parentJoint == model.njoints // 2]
    fixed = [i for i, f in enumerate(model.frames) if f.type == pin.FrameType.FIXED_JOINT]
    for cand in (mid[:1], fixed[-1:]):
        for i in cand:
            if i not in out:
                out.append(i)
    return out


def generate(name, urdf, root, nstates):
    rj = {"fixed": None, "planar": pin.JointModelPlanar(),
          "freeflyer": pin.JointModelFreeFlyer()}[root]
    path = "urdf/" + urdf
    model = pin.buildModelFromUrdf(path) if rj is None else pin.buildModelFromUrdf(path, rj)
    data = model.createData()
    nv = model.nv
    rng = np.random.default_rng(20261122)
    joints = joint_table(model)
    frames = [{"name": f.name, "type": FRAME_TYPES.get(f.type, "universe") if i else "universe",
               "parent_joint": model.names[f.parentJoint]}
              for i, f in enumerate(model.frames)]
    jac_frames = frame_pick(model)
    states = []
    for _ in range(nstates):
        s, q, v = random_state(model, data, rng, coriolis=root != "planar")
        s["kinetic_energy"] = pin.computeKineticEnergy(model, data, q, v)
        s["potential_energy"] = pin.computePotentialEnergy(model, data, q)
        pin.framesForwardKinematics(model, data, q)
        s["frame_placements"] = [
            data.oMf[i].translation.tolist() + data.oMf[i].rotation.flatten().tolist()
            for i in range(model.nframes)]
        s["jacobians"] = [
            {"frame": i, "name": model.frames[i].name,
             "local_world_aligned": np.asarray(pin.computeFrameJacobian(
                 model, data, q, i, pin.LOCAL_WORLD_ALIGNED)).reshape(6, nv).tolist()}
            for i in jac_frames]
        states.append(s)
    out = {
        "_source": "Pinocchio %s outputs (Python bindings), generated by generate_more.py"
                   % pin.__version__,
        "pinocchio_version": pin.__version__, "robot": name, "urdf": "urdf/" + urdf,
        "root_joint": root, "gravity": model.gravity.linear.tolist(), "nq": model.nq,
        "nv": nv, "njoints": model.njoints, "nframes": model.nframes,
        "total_mass": pin.computeTotalMass(model), "joints": joints, "frames": frames,
        "last_body_frame": model.frames[[i for i, f in enumerate(model.frames)
                                         if f.type == pin.FrameType.BODY][-1]].name,
        "lower_position_limit": model.lowerPositionLimit.tolist(),
        "upper_position_limit": model.upperPositionLimit.tolist(),
        "velocity_limit": model.velocityLimit.tolist(),
        "effort_limit": model.effortLimit.tolist(),
        "conventions": "Pinocchio's: planar root q = [x, y, cos, sin] with a base-frame "
                       "velocity; continuous joints q = [cos, sin]; frame_placements rows "
                       "are [x, y, z, R row-major]; Jacobian rows [linear; angular]",
        "states": states,
    }
    with open(name + ".json", "w") as f:
        json.dump(out, f, separators=(",", ":"))


def main():
    robots = sys.argv[1]
    for out, rel, lic in COPIES:
        strip_copy(robots, out, rel, lic)
    for case in CASES:
        generate(*case)


if __name__ == "__main__":
    main()
