"""Ranges of motion from bone names: the name parser, the joint frames and the hard rule, on a Mixamo-named tpose."""

import copy

import numpy as np
import pytest

import supportless as sl
from supportless.search.anatomy import HUMANOID_TABLE, QUADRUPED_TABLE, bone_part, bone_parts, joint_ranges
from supportless.search.naturalness import head_bones, naturalness
from supportless.search.objective import INFEASIBLE

#: The tpose's 15 bones (hips -> chest -> neck -> head, clavicle-arm-forearm, pelvis side-thigh-shin),
#: named as a Mixamo rig names them. The figure faces +z with its left at +x.
MIXAMO_TPOSE = ["mixamorig:Spine", "mixamorig:Neck", "mixamorig:Head",
                "mixamorig:LeftShoulder", "mixamorig:LeftArm", "mixamorig:LeftForeArm",
                "mixamorig:RightShoulder", "mixamorig:RightArm", "mixamorig:RightForeArm",
                "mixamorig:Hips", "mixamorig:LeftUpLeg", "mixamorig:LeftLeg",
                "mixamorig:RightHips", "mixamorig:RightUpLeg", "mixamorig:RightLeg"]
LEFT_SHIN, LEFT_FOREARM, NECK = 11, 5, 1


@pytest.fixture(scope="module")
def named(tpose_rig):
    rig = copy.copy(tpose_rig)
    rig.labels = list(MIXAMO_TPOSE)
    return rig


def _turn(rig, bone, euler_deg):
    """Rest angles with one bone turned by XYZ Euler angles (degrees) relative to its parent."""
    A = np.zeros((rig.bone_count, 3))
    A[bone] = np.radians(euler_deg)
    return A


@pytest.mark.parametrize("name, part, side, group", [
    ("mixamorig:LeftLeg", "shin", "left", None),        # Mixamo
    ("mixamorig:RightForeArm", "forearm", "right", None),
    ("leftLowerLeg", "shin", "left", None),             # VRM
    ("J_Bip_R_UpperArm", "upper_arm", "right", None),    # VRoid
    ("calf_l", "shin", "left", None),                    # Unreal
    ("thigh_r", "thigh", "right", None),
    ("DEF-forearm.L", "forearm", "left", None),          # Rigify
    ("LowerLeg.R", "shin", "right", None),               # Blender / Quaternius
    ("FrontLowerLeg.L", "lower_leg", "left", "front"),   # four legs
    ("BackUpLeg.R", "upper_leg", "right", "back"),
    ("spine_02", "spine", None, None),
    ("mixamorig:LeftHandIndex1", None, "left", None),    # a finger: no table entry
    ("Wing.L", None, "left", None),
    ("Tail3", None, None, None),
    ("mixamorig:LeftLeg>mixamorig:LeftFoot", None, None, None),  # a bone between two named joints
])
def test_bone_names_of_the_usual_conventions(name, part, side, group):
    assert bone_part(name)[:3] == (part, side, group)


def test_a_rig_without_names_has_no_table(tpose_rig):
    assert tpose_rig.labels is None and joint_ranges(tpose_rig) is None


def test_the_humanoid_table_and_the_body_frame(named):
    ranges = joint_ranges(named)
    assert ranges.table == "humanoid" and ranges.convention == "Mixamo"
    assert "humanoid table (Mixamo bone names)" in ranges.describe()
    by_name = dict(zip(ranges.names, range(ranges.count)))
    for joint in ("mixamorig:LeftLeg", "mixamorig:RightLeg", "mixamorig:LeftForeArm", "mixamorig:RightForeArm"):
        assert ranges.kinds[by_name[joint]] == 1  # hinges
    # the knee's hinge is the body's left-right axis; the left elbow's (arm along +x, bending to the front +z) is -y
    knee = by_name["mixamorig:LeftLeg"]
    assert abs(ranges.axis[knee] @ [1.0, 0.0, 0.0]) > 0.99
    elbow = by_name["mixamorig:LeftForeArm"]
    np.testing.assert_allclose(ranges.axis[elbow], [0.0, -1.0, 0.0], atol=0.05)
    assert named.labels[ranges.parent[knee]] == "mixamorig:LeftUpLeg"
    assert named.labels[ranges.parent[by_name["mixamorig:Head"]]] == "mixamorig:Neck"
    rest = named.transforms(np.zeros((named.bone_count, 3)))
    assert ranges.excess(rest) == 0.0  # the rest pose is within every range


def test_a_knee_bent_backwards_is_rejected_and_forwards_within_range_accepted(named):
    """Turning the shin about +x by +40 degrees takes the foot backwards (a knee's bend); -40 forwards."""
    objective = sl.SearchSettings(keep_standing=False, free=("all",)).objective(named)
    generic = sl.SearchSettings(keep_standing=False, free=("all",), anatomy=False).objective(named)
    bent = _turn(named, LEFT_SHIN, (40.0, 0.0, 0.0))
    backwards = _turn(named, LEFT_SHIN, (-40.0, 0.0, 0.0))
    ranges = objective.joint_ranges
    knee = ranges.names.index("mixamorig:LeftLeg")
    foot = named.posed_joints(bent)[named.bones[LEFT_SHIN, 1]]
    assert foot[2] < named.joints[named.bones[LEFT_SHIN, 1], 2] - 5.0  # the foot went backwards (-z)
    assert np.degrees(ranges.measures(named.transforms(bent))["bend"][knee]) == pytest.approx(40.0 + 2.3, abs=2.5)
    assert objective.terms(bent)["violation"] == pytest.approx(0.0)
    assert float(objective(bent)) < INFEASIBLE
    # 40 degrees the wrong way: 35 past the knee's -5 degrees (the rest bend is about 2 degrees)
    over = objective.terms(backwards)["violation"]
    assert np.degrees(over) == pytest.approx(35.0 - 2.3, abs=2.5) and float(objective(backwards)) >= INFEASIBLE
    assert generic.terms(backwards)["violation"] == pytest.approx(0.0)  # the generic 45-degree limit allows it
    use = naturalness(named, backwards)["joint_range"]
    assert use["joint"] == "mixamorig:LeftLeg" and use["measure"] == "bend" and use["share"] > 1.0
    assert use["outside_deg"] == pytest.approx(np.degrees(over), abs=1e-6)


def test_an_elbow_bends_forwards_only_and_in_its_plane(named):
    ranges = joint_ranges(named)
    elbow = ranges.names.index("mixamorig:LeftForeArm")

    def outside(euler):
        return np.degrees(ranges.excess(named.transforms(_turn(named, LEFT_FOREARM, euler))))

    assert outside((0.0, -40.0, 0.0)) == pytest.approx(0.0)  # about -y: the hand comes forwards
    assert outside((0.0, 40.0, 0.0)) == pytest.approx(35.0, abs=1e-6)  # backwards: 35 past -5
    assert outside((0.0, 0.0, 30.0)) == pytest.approx(20.0, abs=1e-6)  # up, out of its plane: 20 past 10
    assert outside((60.0, 0.0, 0.0)) == pytest.approx(0.0)  # a forearm's twist up to 80
    assert outside((100.0, 0.0, 0.0)) == pytest.approx(20.0, abs=1e-6)
    m = ranges.measures(named.transforms(_turn(named, LEFT_FOREARM, (100.0, 0.0, 0.0))))
    assert np.degrees(m["twist"][elbow]) == pytest.approx(100.0, abs=1e-6)


def test_a_batch_equals_its_single_poses_and_rigid_motion_of_the_whole_body_costs_nothing(named):
    ranges = joint_ranges(named)
    rng = np.random.default_rng(3)
    A = rng.uniform(-0.9, 0.9, (6, named.bone_count, 3))
    batch = ranges.excess(named.transforms(A))
    singles = [ranges.excess(named.transforms(a)) for a in A]
    np.testing.assert_allclose(batch, singles, atol=1e-12)
    root = int(np.flatnonzero(named.parents < 0)[0])
    whole = _turn(named, root, (50.0, -70.0, 30.0))  # the root turns: every bone with it, no joint bends
    assert ranges.excess(named.transforms(whole)) == pytest.approx(0.0, abs=1e-9)


def test_a_search_keeps_every_named_joint_in_range(named):
    found = sl.optimize(named, particles=24, iterations=6, seed=1, orient="keep", free=("all",),
                        keep_standing=False, joint_limit=90.0)
    assert naturalness(named, found.angles)["joint_range"]["outside_deg"] == pytest.approx(0.0, abs=1e-9)
    assert found.settings.anatomy


@pytest.mark.parametrize("neck, head", [
    ("mixamorig:Neck", "mixamorig:Head"),     # Mixamo
    ("neck", "head"),                         # VRM, Unreal
    ("neck_01", "head"),                      # Unreal
    ("J_Bip_C_Neck", "J_Bip_C_Head"),         # VRoid's centre bones
    ("DEF-neck", "DEF-head"),                 # Blender
    ("Neck", "Head"),                         # Quaternius
    ("b_Neck_04", "b_Head_05"),               # the Fox, four legs
    ("CC_Base_NeckTwist01", "CC_Base_Head"),  # Character Creator
])
def test_every_naming_scheme_names_its_neck_and_head(neck, head):
    assert (bone_part(neck)[0], bone_part(head)[0]) == ("neck", "head")
    assert [p[0] for p in bone_parts(["spine", neck, head])] == ["spine", "neck", "head"]


def test_rigify_names_its_neck_and_head_by_the_spine_numbers():
    spine = [f"DEF-spine.{i:03d}" if i else "DEF-spine" for i in range(7)]
    assert [p[0] for p in bone_parts(spine)] == ["spine"] * 4 + ["neck", "neck", "head"]
    assert [p[0] for p in bone_parts(spine[:5])] == ["spine"] * 5  # a spine that does not end at .006


def test_the_tables_hold_a_neck_and_a_head_with_small_cones():
    for table in (HUMANOID_TABLE, QUADRUPED_TABLE):
        for part in ("neck", "head"):
            assert table[part].kind == "ball" and 25.0 <= table[part].swing <= 45.0 and table[part].twist <= 45.0


#: The tpose named as VRoid and Rigify name their bones (Mixamo's is :data:`MIXAMO_TPOSE`).
VROID_TPOSE = ["J_Bip_C_Chest", "J_Bip_C_Neck", "J_Bip_C_Head",
               "J_Bip_L_Shoulder", "J_Bip_L_UpperArm", "J_Bip_L_LowerArm",
               "J_Bip_R_Shoulder", "J_Bip_R_UpperArm", "J_Bip_R_LowerArm",
               "J_Bip_C_Hips", "J_Bip_L_UpperLeg", "J_Bip_L_LowerLeg",
               "J_Bip_R_Hips", "J_Bip_R_UpperLeg", "J_Bip_R_LowerLeg"]
RIGIFY_TPOSE = ["DEF-spine.003", "DEF-spine.004", "DEF-spine.006",
                "DEF-shoulder.L", "DEF-upper_arm.L", "DEF-forearm.L",
                "DEF-shoulder.R", "DEF-upper_arm.R", "DEF-forearm.R",
                "DEF-spine", "DEF-thigh.L", "DEF-shin.L",
                "DEF-pelvis.R", "DEF-thigh.R", "DEF-shin.R"]


@pytest.mark.parametrize("labels", [MIXAMO_TPOSE, VROID_TPOSE, RIGIFY_TPOSE], ids=["Mixamo", "VRoid", "Rigify"])
def test_a_named_figure_ranges_its_neck_and_head_and_bounds_its_head(tpose_rig, labels):
    rig = copy.copy(tpose_rig)
    rig.labels = list(labels)
    ranges = joint_ranges(rig)
    assert ranges.table == "humanoid" and {NECK, NECK + 1} <= set(ranges.child.tolist())
    assert ranges.parent[ranges.child.tolist().index(NECK + 1)] == NECK  # the head turns on the neck
    assert head_bones(rig).tolist() == [NECK + 1]
    objective = sl.SearchSettings(keep_standing=False, free=("all",)).objective(rig)
    nod = np.zeros((rig.bone_count, 3))
    nod[[NECK, NECK + 1], 0] = np.radians(20.0)  # each joint well within its range, the head 40 degrees down
    assert ranges.excess(rig.transforms(nod)) == pytest.approx(0.0)
    assert objective.terms(nod)["violation"] == pytest.approx(np.radians(15.0))


@pytest.mark.parametrize("name, part, side, convention", [
    ("Bip01 L UpperArm", "upper_arm", "left", "3ds Max Biped"),   # 3ds Max Biped
    ("Bip001 R Forearm", "forearm", "right", "3ds Max Biped"),
    ("Bip01 Head", "head", None, "3ds Max Biped"),
    ("ValveBiped.Bip01_R_Thigh", "thigh", "right", "3ds Max Biped"),  # Source engine
    ("Character1_LeftArm", "upper_arm", "left", "Left/Right"),      # HumanIK / MotionBuilder
    ("Character1_Neck", "neck", None, "plain"),
    ("lShldrBend", "upper_arm", "left", "DAZ"),                     # DAZ Genesis
    ("rForearmBend", "forearm", "right", "DAZ"),
    ("lCollar", "shoulder", "left", "DAZ"),
    ("rThighBend", "thigh", "right", "DAZ"),
    ("chestUpper", "spine", None, "plain"),
])
def test_more_naming_schemes_name_their_limbs(name, part, side, convention):
    assert bone_part(name)[:2] == (part, side)
    assert bone_part(name)[3] == convention


@pytest.mark.parametrize("name", ["Root", "RigRoot", "LowerBody", "Ribbon", "lShldrTwist"])
def test_names_that_only_look_like_a_side_letter_are_not_limbs(name):
    assert bone_part(name)[0] not in ("upper_arm", "forearm", "thigh", "shin")
