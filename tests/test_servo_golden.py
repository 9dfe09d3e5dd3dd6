"""Golden values of short servo runs: a refactor of the simulations cannot change their numbers silently.

Each run's key outputs (for every recorded series: its first and last entry and its NaN-ignoring sum at a few
fixed steps) were taken from the code of commit ed6d9a6, before ``simulate_pinhole`` and ``simulate_panoramic``
were split into control law, state update and recording, by running this file as a script::

    .venv/bin/python tests/test_servo_golden.py

which prints ``GOLDEN`` for the runs in ``RUNS``. Regenerate only for an intended change of the numbers, and
say so in the commit.

They are compared for what a run means, not for the BLAS build that ran it: the steps, the outcome and the
reason's words exactly, the numbers the reason prints numerically, and every float (final errors, series) at a
tolerance derived on this machine from the loop's own conditioning (:mod:`_servo_conditioning`: twin runs
re-rounded at every step), never below rtol 1e-9. A fixed 1e-9 compared the OpenBLAS kernel instead: the closed
loop amplifies its last-bit differences, up to 1e-8 in the panoramic runs. The tolerances stay far below a real
change: a gain off by 1e-6, or any golden value nudged by 1e-6, fails the same comparison (tested below).
"""

from __future__ import annotations

import functools
import inspect
from typing import Any

import numpy as np
import pytest

import _servo_conditioning as conditioning
from egtviz.servo import ServoResult, simulate_panoramic, simulate_pinhole

#: name -> (demo, keyword arguments): the defaults, rotation only with the linearised step, and noise with an
#: estimated F for the arm; the defaults and noise for the robot.
RUNS: dict[str, tuple[str, dict[str, Any]]] = {
    "pinhole_default": ("pinhole", {"seed": 2, "steps": 30}),
    "pinhole_beta0_linearized": ("pinhole", {"seed": 5, "beta": 0.0, "priority": "linearized", "steps": 30}),
    "pinhole_noise_normalized_F": ("pinhole", {"seed": 1, "noise_px": 0.5, "f_algorithm": 2, "steps": 20}),
    "panoramic_default": ("panoramic", {"seed": 0, "steps": 40}),
    "panoramic_noise": ("panoramic", {"seed": 2, "noise_px": 1.0, "steps": 40, "conic_every": 7}),
}

#: Series compared without their sign: with an estimated F the epipole is F's null vector, whose sign rounding
#: decides (OpenBLAS differs in the last bits from one process to another), and the signed distances to the
#: epipolar lines follow it.
SIGN_FREE = ("extras.epipolar_distances_px",)

#: Steps at which each time series is sampled (clipped to the run's length).
STEPS = (0, 7, 19, -1)


def series_of(result: ServoResult) -> dict[str, np.ndarray]:
    """Every recorded array of ``result`` by a dotted name, time first."""
    out = {"time": result.time, "camera_poses": result.camera_poses, "features": result.features}
    for group in ("controls", "errors", "extras"):
        out.update({f"{group}.{k}": np.asarray(v) for k, v in getattr(result, group).items()})
    for name in ("joint_angles", "states"):
        if getattr(result, name) is not None:
            out[name] = getattr(result, name)
    return out


def key_values(result: ServoResult) -> dict[str, Any]:
    """The summary and, per series, ``[first, last, nansum]`` of its row (or its value) at each of :data:`STEPS`.

    A 1-D series that is not over time (the target state or joints) is one row; an array that is not over time
    (scene points, bi-conics) is sampled along its first axis alike; a boolean series gives its count of ``True``;
    a series of :data:`SIGN_FREE` is taken in absolute value.
    """
    out: dict[str, Any] = {
        "steps": result.steps,
        "converged": result.converged,
        "reason": result.reason,
        "final_rotation_error_rad": result.final_rotation_error_rad,
        "final_translation_error": result.final_translation_error,
        "desired_features": [float(result.desired_features[0, 0]), float(np.sum(result.desired_features))],
    }
    for name, arr in series_of(result).items():
        if arr.dtype == bool:
            out[name] = int(np.count_nonzero(arr))
            continue
        arr = arr.astype(float)
        if name in SIGN_FREE:
            arr = np.abs(arr)
        if arr.ndim <= 1 and len(arr) != result.n_samples:
            rows = [arr.ravel()]
        else:
            steps = dict.fromkeys(min(k, len(arr) - 1) if k >= 0 else len(arr) + k for k in STEPS)
            rows = [arr[k].ravel() for k in steps]
        out[name] = [_row_values(r) for r in rows if r.size]
    return out


def _row_values(row: np.ndarray) -> float | list[float]:
    if row.size == 1:
        return float(row[0])
    return [float(row[0]), float(row[-1]), float(np.nansum(row))]


def run(name: str) -> ServoResult:
    demo, kwargs = RUNS[name]
    return (simulate_pinhole if demo == "pinhole" else simulate_panoramic)(**kwargs)


GOLDEN: dict[str, dict[str, Any]] = {
    'pinhole_default': {
        'steps': 30,
        'converged': False,
        'reason': (
            'not converged after 30 steps: rotation error 3.30e-03 rad (tol 0.001), translation error '
            '2.41e-01 m (tol 0.001)'
        ),
        'final_rotation_error_rad': 0.0032951215207365427,
        'final_translation_error': 0.24054940107056802,
        'desired_features': [322.97857275790926, 6681.461159607417],
        'time': [0.0, 0.35000000000000003, 0.9500000000000001, 1.5],
        'camera_poses': [
            [-0.22216972784763855, 1.0, -0.18302960722870376],
            [-0.07135774266430975, 1.0, -0.31234604013149314],
            [-0.009105768086935417, 1.0, -0.3576602445340301],
            [-0.0012301693836071978, 1.0, -0.34289919843493155],
        ],
        'features': [
            [332.9914794176865, 240.17241604453957, 6681.408647250593],
            [348.02400504846446, 217.6065710654194, 6586.328296620993],
            [351.34108012777637, 212.0299736872552, 6555.66100381636],
            [348.8815120180704, 215.1246553690289, 6561.06311797109],
        ],
        'controls.camera_twist': [
            [0.021120634388013523, -0.6627795877413957, -1.9993408852732553],
            [0.03605769565736778, -0.20864768893520025, -0.6096066995433985],
            [0.03526202950335471, -0.02573042556809539, -0.05083514206711416],
            [0.03030587416584906, -0.002727448805881786, 0.019667856242529258],
        ],
        'controls.joint_velocities': [
            [-0.9939543648423319, -1.347069471621388, -3.6237984720184393],
            [-0.5924888741665038, -0.7120922883309091, -2.014236321016676],
            [-0.27728713309470093, -0.22831825959617927, -0.7391933205687997],
            [-0.1720906889209212, -0.10994342029248595, -0.40955852102316803],
        ],
        'errors.task_error_norm': [
            0.29497678574259684,
            0.08174761849438922,
            0.014002775859769969,
            0.002821569962233573,
        ],
        'errors.rotation_error_rad': [
            0.41323526704174923,
            0.13509587698518385,
            0.01938298630966115,
            0.0032951215207365427,
        ],
        'errors.translation_error': [
            0.3800301636004179,
            0.34171619088075905,
            0.28437105004858104,
            0.24054940107056802,
        ],
        'errors.feature_error_px': [19.459568129048172, 35.4780449645913, 44.46446154932255, 41.242605474090546],
        'errors.max_epipolar_distance_px': [
            24.77773805734575,
            7.759072355654633,
            1.2959665859369542,
            0.2556639114063247,
        ],
        'extras.features_true': [
            [332.9914794176865, 240.17241604453957, 6681.408647250593],
            [348.02400504846446, 217.6065710654194, 6586.328296620993],
            [351.34108012777637, 212.0299736872552, 6555.66100381636],
            [348.8815120180704, 215.1246553690289, 6561.06311797109],
        ],
        'extras.epipolar_distances_px': [
            [3.020464553046962, 11.411368157260444, 143.02896216978812],
            [2.6199658810509994, 1.2725527119901243, 36.99834597474665],
            [0.5372338294855816, 0.01977276150505104, 6.1846456599471376],
            [0.09961192299630155, 0.02275181597226463, 1.3536199568120861],
        ],
        'extras.epipole_px': [
            [351.710840321359, 1.0, 516.5841472818696],
            [390.9903897284145, 1.0, 517.1156025099003],
            [411.5741375113321, 1.0, 517.6716781935271],
            [414.2831195836747, 1.0, 517.3892081737566],
        ],
        'extras.manipulability': [
            0.01852265044979508,
            0.025825970819304392,
            0.03677918935340338,
            0.04451436655420415,
        ],
        'extras.joint_limit_clipped': 0,
        'extras.exact_priority_step': 31,
        'extras.scene_points': [
            [0.8765378938972326, 0.0700036442627533, 0.7884547100657247],
            [1.1358335335991248, 0.1805888703323956, 1.2588956932984898],
            [1.0040774418087899, 0.09380220460233385, 0.8175833182655936],
        ],
        'extras.target_pose': [
            [0.0, 0.5863293355684915, 0.9523547393529299],
            [0.0, 1.0, 1.0],
        ],
        'extras.target_q': [
            [0.0, 0.0, -2.0943951023931953],
        ],
        'joint_angles': [
            [0.9932132188113861, 0.8204152529758234, 0.7263046718405367],
            [0.7014240416896637, 0.43702663565792155, -0.3123366884558858],
            [0.45200914399461006, 0.17877433564400638, -1.0804820814954474],
            [0.32931792957221195, 0.08812178745700867, -1.3902748043355906],
        ],
    },
    'pinhole_beta0_linearized': {
        'steps': 30,
        'converged': False,
        'reason': (
            'translation not servoed (beta = 0): only the priority (rotation) task acts; rotation error '
            '5.95e-03 rad is above 0.001'
        ),
        'final_rotation_error_rad': 0.005950315939026109,
        'final_translation_error': 0.2507688034601595,
        'desired_features': [322.97857275790926, 6681.461159607417],
        'time': [0.0, 0.35000000000000003, 0.9500000000000001, 1.5],
        'camera_poses': [
            [-0.1459841851962487, 1.0, 0.24199475605235654],
            [-0.06765771060483446, 1.0, -0.053857084971524416],
            [-0.006659038596536014, 1.0, -0.36441603139351053],
            [-0.0009998633156472168, 1.0, -0.4028361403911809],
        ],
        'features': [
            [323.24471738326235, 258.86790263417134, 6673.8829471343715],
            [340.6503396150105, 221.76068807810663, 6428.194648145795],
            [353.6750626887711, 181.08301862425085, 6065.638089960761],
            [355.27117867420446, 175.34134879415947, 6009.667335802906],
        ],
        'controls.camera_twist': [
            [0.0, 0.670206962030831, -0.42200404511959755],
            [0.0, 0.1923663050096419, -0.6474289144129068],
            [0.0, 0.02390401717125371, -0.12079647025466236],
            [0.0, 0.0040796385783550635, -0.018261039567460217],
        ],
        'controls.joint_velocities': [
            [-0.03195855406019038, 0.7043833415766863, -0.34360915762607935],
            [-0.030248319806805812, 0.2523155177821972, -0.6120557919186266],
            [-0.006053514990942296, 0.045645363233389864, -0.1150139825774979],
            [-0.0009518653196082805, 0.007795322496115073, -0.017352932248163436],
        ],
        'errors.task_error_norm': [
            0.159418232153152,
            0.05800892579077433,
            0.009735820398974974,
            0.0016551017852596377,
        ],
        'errors.rotation_error_rad': [
            0.5485928537740687,
            0.28521688462228845,
            0.03699887636267062,
            0.005950315939026109,
        ],
        'errors.translation_error': [
            0.25074235659208083,
            0.25078300158910327,
            0.2507696834477802,
            0.2507688034601595,
        ],
        'errors.feature_error_px': [13.259295459640938, 36.17642409331561, 80.62383445198081, 87.0060591715993],
        'errors.max_epipolar_distance_px': [
            16.511957683809985,
            7.270571536805905,
            1.3387333942994668,
            0.22964881439395465,
        ],
        'extras.features_true': [
            [323.24471738326235, 258.86790263417134, 6673.8829471343715],
            [340.6503396150105, 221.76068807810663, 6428.194648145795],
            [353.6750626887711, 181.08301862425085, 6065.638089960761],
            [355.27117867420446, 175.34134879415947, 6009.667335802906],
        ],
        'extras.epipolar_distances_px': [
            [7.49525272088279, 2.0916465436693805, 71.66157512772898],
            [1.1400369683079261, 0.29137687249452393, 20.94574272650921],
            [0.18359931459494122, 0.17925370816605493, 3.533815196896981],
            [0.03476105454685044, 0.030980911426834266, 0.6066721140427659],
        ],
        'extras.epipole_px': [
            [569.1305335652594, 1.0, 370.32835726788494],
            [1235.972784464716, 1.0, -892.777208699818],
            [66.18834884740761, 1.0, 1074.0173306100032],
            [107.51415746864566, 1.0, 1005.5047515223022],
        ],
        'extras.manipulability': [0.07877838322763693, 0.07576713609682982, 0.06838957424763414, 0.06716202579040804],
        'extras.joint_limit_clipped': 0,
        'extras.exact_priority_step': 0,
        'extras.scene_points': [
            [0.8765378938972326, 0.0700036442627533, 0.7884547100657247],
            [1.1358335335991248, 0.1805888703323956, 1.2588956932984898],
            [1.0040774418087899, 0.09380220460233385, 0.8175833182655936],
        ],
        'extras.target_pose': [
            [0.0, 0.5863293355684915, 0.9523547393529299],
            [0.0, 1.0, 1.0],
        ],
        'extras.target_q': [
            [0.0, 0.0, -2.0943951023931953],
        ],
        'joint_angles': [
            [0.18822507364718866, -0.27853943091488953, -1.341788285595034],
            [0.17812910554962116, -0.1150601706722688, -1.4854482026096396],
            [0.16604359874323552, -0.03373350102046498, -1.7371294172665197],
            [0.1644094811793951, -0.020949210030210566, -1.7676214568169912],
        ],
    },
    'pinhole_noise_normalized_F': {
        'steps': 20,
        'converged': False,
        'reason': (
            'not converged after 20 steps: rotation error 1.49e-01 rad (tol 0.01), translation error '
            '2.95e-01 m (tol 0.01)'
        ),
        'final_rotation_error_rad': 0.14861953435168826,
        'final_translation_error': 0.2945241581226537,
        'desired_features': [323.27799586422657, 6680.741309174435],
        'time': [0.0, 0.35000000000000003, 0.9500000000000001, 1.0],
        'camera_poses': [
            [-0.6353812930713385, 1.0, -0.4349311733546315],
            [-0.26796624121541296, 1.0, -0.22517203362509308],
            [-0.09403768278841204, 1.0, 0.05255059062806278],
            [-0.0939681466468002, 1.0, 0.05156492564839743],
        ],
        'features': [
            [343.7529290215827, 229.05836171239497, 6652.753082694202],
            [374.0021402486976, 290.50558914325626, 7736.031702845763],
            [376.6175402118626, 315.44557513497494, 8040.327215772998],
            [374.32920835652243, 314.49530623044035, 8019.644999151946],
        ],
        'controls.camera_twist': [
            [0.09331338330043762, -1.2917999092816814, -0.7887423486190199],
            [0.07407611611699524, -0.2754770384435912, -0.1211029953284542],
            [0.05396952688889946, -0.07611930753653844, 0.19098873810056122],
            [0.05294694882376627, 0.04276429286007407, -0.02918256498274272],
        ],
        'controls.joint_velocities': [
            [-0.022021714301847073, -0.29795692732518814, -5.074631802983507],
            [-0.08856064442799697, 1.2436212983795647, -2.2671186416343634],
            [-0.04543261298073609, 0.7749062659982779, -0.24890103451499024],
            [-0.059874436389582564, 0.5014199059388642, -0.32988649928711977],
        ],
        'errors.task_error_norm': [0.2518733991733396, 0.21200202800525775, 0.18495894839645405, 0.20710011226946523],
        'errors.rotation_error_rad': [
            0.8994929787112691,
            0.36602237558524087,
            0.14849478909491653,
            0.14861953435168826,
        ],
        'errors.translation_error': [0.39986592963524387, 0.3589073657307626, 0.2989978064133725, 0.2945241581226537],
        'errors.feature_error_px': [22.970038890016223, 63.29847016037437, 82.37014587123271, 81.39191610247548],
        'errors.max_epipolar_distance_px': [
            23.654593734019418,
            16.031752547200334,
            11.774093220694418,
            12.922374899893391,
        ],
        'extras.features_true': [
            [343.69842197767196, 229.54945577486546, 6654.548219115928],
            [373.06856749140724, 290.3259668172507, 7739.051172054267],
            [376.80714715336893, 315.07455305532727, 8042.099459601588],
            [374.86285547300844, 314.97837264042516, 8018.768843708506],
        ],
        'extras.epipolar_distances_px': [
            [19.761513323282525, 12.145186485197696, 110.56797534821061],
            [4.549611089720113, 6.511735255751481, 114.51037680932775],
            [8.596533219116537, 10.568943751967696, 112.16170368202874],
            [12.472000220602526, 10.31933567843482, 128.58834693510252],
        ],
        'extras.epipole_px': [
            [953.0513856976694, 1.0, 1552.6115205031172],
            [5071.145326744449, 1.0, 10304.170919305161],
            [51.11729541413007, 1.0, -51.09625357134091],
            [-57.21860100793056, 1.0, -291.50451115152333],
        ],
        'extras.manipulability': [0.07949635851230726, 0.06101971836743457, 0.0401443721070176, 0.04063989802542207],
        'extras.joint_limit_clipped': 0,
        'extras.exact_priority_step': 21,
        'extras.scene_points': [
            [0.8765378938972326, 0.0700036442627533, 0.7884547100657247],
            [1.1358335335991248, 0.1805888703323956, 1.2588956932984898],
            [1.0040774418087899, 0.09380220460233385, 0.8175833182655936],
        ],
        'extras.target_pose': [
            [0.0, 0.5863293355684915, 0.9523547393529299],
            [0.0, 1.0, 1.0],
        ],
        'extras.target_q': [
            [0.0, 0.0, -2.0943951023931953],
        ],
        'joint_angles': [
            [0.3089510914447163, -1.954069504497654, 0.15277065475125085],
            [0.28931352226975243, -1.8682641738111516, -0.9838263399345436],
            [0.25156896737667134, -1.2737148908261142, -1.5301549786366846],
            [0.24929733672763454, -1.2349695775262004, -1.542600030362435],
        ],
    },
    'panoramic_default': {
        'steps': 40,
        'converged': False,
        'reason': (
            'not converged after 40 steps (phase 1): rotation error 2.25e-02 rad (tol 0.001), '
            'translation error 1.08e+00 m (tol 0.001)'
        ),
        'final_rotation_error_rad': 0.022528073211472766,
        'final_translation_error': 1.0819470478723894,
        'desired_features': [374.5845487421558, 5716.653716428004],
        'time': [0.0, 0.35000000000000003, 0.9500000000000001, 2.0],
        'camera_poses': [
            [0.046643542758369794, 1.0, 1.4050144200257155],
            [0.7458479243069176, 1.0, 2.8034231831228116],
            [0.9788797995946825, 1.0, 3.2694869336983414],
            [0.9997462536906139, 1.0, 3.311219841890204],
        ],
        'features': [
            [328.356645384543, 233.7945201136873, 5205.862898789913],
            [364.97167457041166, 190.52330029225593, 5477.727524443344],
            [375.14322487594933, 177.24188173531311, 5709.956035188673],
            [375.239865577975, 176.5095085726424, 5787.505604375805],
        ],
        'controls.robot_velocity': [
            [0.0, -3.0482717111807895, -3.0482717111807895],
            [0.0, -1.4579789108270411, -1.4579789108270411],
            [0.0, -0.4117763070826177, -0.4117763070826177],
            [0.0, -0.04505614721730211, -0.04505614721730211],
        ],
        'errors.task_error_norm': [1.5309337454615657, 0.7430973373848222, 0.2513124716478661, 0.14586137505300412],
        'errors.rotation_error_rad': [
            1.5241358543519183,
            0.7289894538171673,
            0.2058881530757377,
            0.022528073211472766,
        ],
        'errors.translation_error': [1.0819470478723894, 1.0819470478723894, 1.0819470478723894, 1.0819470478723894],
        'errors.feature_error_px': [86.39853219410789, 42.811036373422844, 10.771841659405407, 8.986452612785966],
        'extras.s_px': [86.39853219410789, 42.811036373422844, 10.771841659405407, 8.986452612785966],
        'extras.s_angle_rad': [0.1441111609026623, 0.1441111609984144, 0.14411116069586677, 0.14411116067756977],
        'extras.alpha_hat': [-1.5241358555903948, -0.7289894554135206, -0.20588815354130885, -0.022528073608651056],
        'extras.biconic_measure': [
            0.1032552382722276,
            0.031561145141425495,
            0.003787454803366036,
            2.9562402575233904e-05,
        ],
        'extras.phase': [1.0, 1.0, 1.0, 1.0],
        'extras.biconics': [
            [-6.432095546406851e-06, -0.9999932487411879, -9.928649612350565],
            [-6.936903216531663e-06, -0.9999933845458961, -9.92727580294211],
        ],
        'extras.biconic_steps': [
            [0.0, 40.0, 100.0],
        ],
        'extras.scene_points': [
            [4.928519033896988, 0.22887565370345614, 5.676146060485088],
            [4.374833606096534, 2.142296754160672, 4.5094683738238555],
            [-0.8465758968181755, 0.9094346286906199, -4.529138465967463],
        ],
        'extras.target_state': [
            [0.0, 0.0, 0.0],
        ],
        'states': [
            [-1.0761184126111472, 1.5241358543519183, 0.33586318886089495],
            [-1.0761184126111472, 0.7289894538171673, -0.4592832116738561],
            [-1.0761184126111472, 0.2058881530757377, -0.9823845124152857],
            [-1.0761184126111472, 0.022528073211472766, -1.1657445922795506],
        ],
    },
    'panoramic_noise': {
        'steps': 40,
        'converged': False,
        'reason': (
            'not converged after 40 steps (phase 2): rotation error 1.74e-02 rad (tol 0.01), '
            'translation error 2.38e+00 m (tol 0.01)'
        ),
        'final_rotation_error_rad': 0.017361203422257887,
        'final_translation_error': 2.3775521503127846,
        'desired_features': [376.3842561248767, 5720.618393328801],
        'time': [0.0, 0.35000000000000003, 0.9500000000000001, 2.0],
        'camera_poses': [
            [0.5941899629929046, 1.0, 0.05121174344746526],
            [0.9042556064939338, 1.0, 0.6713430304495236],
            [0.9909741022877583, 1.0, 0.8447800220371726],
            [0.9998492980931948, 1.0, 1.2108281847013753],
        ],
        'features': [
            [339.13715946211363, 223.98971682052743, 6137.677480490358],
            [363.18458292009365, 196.8414117658074, 6083.722463099274],
            [371.8188309012932, 183.54726384584717, 5984.527229966289],
            [372.4538837973111, 179.10241990599647, 5924.482039829253],
        ],
        'controls.robot_velocity': [
            [0.0, 1.9195844206581754, 1.9195844206581754],
            [0.0, 0.8178535232148763, 0.8178535232148763],
            [0.0, 0.15549592365375364, 0.15549592365375364],
            [0.7890338255372084, 0.11295386392148021, 1.3435422219678195],
        ],
        'errors.task_error_norm': [1.0183815317526503, 0.5509416817699923, 0.37888454118379633, 0.3066397773744955],
        'errors.rotation_error_rad': [
            0.9345381551220981,
            0.4411631811988608,
            0.13445823361013343,
            0.017361203422257887,
        ],
        'errors.translation_error': [2.6284514811885606, 2.6284514811885606, 2.6284514811885606, 2.3775521503127846],
        'errors.feature_error_px': [69.28455170772847, 41.01456555659701, 26.943262702040197, 21.632366023062495],
        'extras.s_px': [69.28455170772847, 41.01456555659701, 26.943262702040197, 21.632366023062495],
        'extras.s_angle_rad': [0.34044068089239643, 0.3692094803127363, 0.3708217226374722, 0.3013939435764795],
        'extras.alpha_hat': [0.9597922103290877, 0.4089267616074381, 0.07774796182687682, 0.05647693196074011],
        'extras.biconic_measure': [
            0.04671381769232674,
            0.011938839166101278,
            0.0011669826215469081,
            0.001340647306232401,
        ],
        'extras.phase': [1.0, 1.0, 1.0, 2.0],
        'extras.biconics': [
            [-6.439912507156758e-06, -0.9999935030325856, -9.92933634096767],
            [-6.678673713793458e-06, -0.999993494399335, -9.928411109029092],
        ],
        'extras.biconic_steps': [
            [0.0, 40.0, 145.0],
        ],
        'extras.scene_points': [
            [4.928519033896988, 0.22887565370345614, 5.676146060485088],
            [4.374833606096534, 2.142296754160672, 4.5094683738238555],
            [-0.8465758968181755, 0.9094346286906199, -4.529138465967463],
        ],
        'extras.target_state': [
            [0.0, 0.0, 0.0],
        ],
        'states': [
            [-2.2021600256861387, -0.9345381551220981, -4.5717063376604425],
            [-2.2021600256861387, -0.4411631811988608, -4.078331363737204],
            [-2.2021600256861387, -0.13445823361013343, -3.7716264161484774],
            [-1.9940206285551167, -0.017361203422257887, -3.3062316149072726],
        ],
    },
}


#: What a run means: its length, its outcome and why, and where it ended.
MEANING = ("steps", "converged", "reason", *conditioning.FINAL_ERRORS)

#: Relative size of a real change that every comparison must see (a gain, or a golden value, off by this much).
REAL_CHANGE = 1e-6

#: The keyword argument of each demo's main gain (the control law's lambda / k_omega).
GAIN = {"pinhole": "gain", "panoramic": "k_omega"}


@functools.cache
def measured(name: str) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The run's key values on this machine and each float value's tolerance from its twin runs (cached:
    every test of a run shares one nominal run and its twins)."""
    return conditioning.derived_tolerances(lambda: key_values(run(name)), GOLDEN[name])


@pytest.mark.parametrize("name", list(RUNS))
def test_short_runs_mean_what_they_meant(name):
    """Steps and outcome exactly, the reason's words exactly and its numbers, and the final errors."""
    got, tol = measured(name)
    assert got.keys() == GOLDEN[name].keys()
    assert conditioning.mismatches(got, GOLDEN[name], tol, list(MEANING)) == []


@pytest.mark.parametrize("name", list(RUNS))
def test_short_runs_keep_their_golden_series(name):
    """Every recorded series (and the desired features) at the tolerance derived from the loop's conditioning."""
    got, tol = measured(name)
    others = [key for key in GOLDEN[name] if key not in MEANING]
    assert conditioning.mismatches(got, GOLDEN[name], tol, others) == []


@pytest.mark.parametrize("name", list(RUNS))
def test_a_changed_gain_is_detected(name):
    """The same comparison sees the control law's gain changed by REAL_CHANGE relative: the derived tolerances
    are about rounding, not about the law."""
    _, tol = measured(name)
    demo, kwargs = RUNS[name]
    simulate = simulate_pinhole if demo == "pinhole" else simulate_panoramic
    # The runs use the default gain: read it from the signature so that the change stays 1e-6 of it.
    gain = inspect.signature(simulate).parameters[GAIN[demo]].default
    got = key_values(simulate(**{**kwargs, GAIN[demo]: gain * (1.0 + REAL_CHANGE)}))
    found = conditioning.mismatches(got, GOLDEN[name], tol, list(GOLDEN[name]))
    assert any(m.startswith(conditioning.FINAL_ERRORS) for m in found), found
    assert any(m.startswith(("states", "joint_angles")) for m in found), found


@pytest.mark.parametrize("name", list(RUNS))
def test_a_nudged_golden_value_is_detected(name):
    """Every non-zero golden value, nudged alone by REAL_CHANGE relative, fails the same comparison: no value's
    derived tolerance is a blanket loosening."""
    got, tol = measured(name)
    expected = GOLDEN[name]
    for key, value in expected.items():
        if not conditioning.is_float_value(value):
            continue
        flat = np.asarray(value, dtype=float).ravel()
        for i in np.flatnonzero(flat):
            nudged = flat.copy()
            nudged[i] *= 1.0 + REAL_CHANGE
            changed = {**expected, key: nudged.reshape(np.shape(value)).tolist()}
            assert conditioning.mismatches(got, changed, tol, [key]), f"{key}[{i}]: a nudge of {REAL_CHANGE} unseen"


@pytest.mark.parametrize("name", list(RUNS))
def test_a_changed_reason_is_detected(name):
    """The reason's words are compared exactly and its printed errors numerically: one word, or a printed final
    error one unit off in its last digit, fails."""
    got, tol = measured(name)
    expected = GOLDEN[name]
    reworded = {**got, "reason": got["reason"].replace("error", "errors", 1)}
    assert conditioning.mismatches(reworded, expected, tol, ["reason"])
    printed = [n for n in conditioning.NUMBER.findall(got["reason"]) if "e" in n]
    for number in printed:
        mantissa, exponent = number.split("e")
        off = f"{float(mantissa) + 0.01:.2f}e{exponent}"
        changed = {**got, "reason": got["reason"].replace(number, off, 1)}
        assert conditioning.mismatches(changed, expected, tol, ["reason"]), off


def _source_of(name: str, values: dict[str, Any]) -> str:
    """``values`` as the lines of a ``GOLDEN`` entry (one row per line, at most 120 characters)."""
    out = [f"    {name!r}: {{"]
    for key, value in values.items():
        if isinstance(value, list) and (isinstance(value[0], list) or len(f"        {key!r}: {value!r},") > 118):
            out += [f"        {key!r}: [", *(f"            {row!r}," for row in value), "        ],"]
        elif isinstance(value, str) and len(value) > 90:
            parts, line = [], ""
            for word in value.split(" "):
                if line and len(line) + len(word) + 1 > 90:
                    parts.append(line + " ")
                    line = word
                else:
                    line = f"{line} {word}" if line else word
            out += [f"        {key!r}: (", *(f"            {p!r}" for p in [*parts, line]), "        ),"]
        else:
            out.append(f"        {key!r}: {value!r},")
    return "\n".join([*out, "    },"])


if __name__ == "__main__":
    print("GOLDEN: dict[str, dict[str, Any]] = {")
    for run_name in RUNS:
        print(_source_of(run_name, key_values(run(run_name))))
    print("}")
