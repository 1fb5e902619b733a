"""Joint axes and DH parameters from tracked link trajectories (paper, Sect. "Kinematic
Parameters Identification"): PCA and circle fits per link, projection into the moving
frame of the previous joint, DH parameters from the identified lines."""

from .branches import LinkAxisFit, fit_link_axis, identify_branch, project_into_previous_frame
from .circle_fit import CircleFit, IdentificationError, fit_circle
from .loop import IdentifiedLoop, bennett_ratios, identify_axes, identify_dh, identify_loop
from .records import LinkRecord, clean_record, moving_average, read_simulation_result, read_vicon_csv
from .runs import RecordIdentification, RunStatistics, identify_record, run_statistics

__all__ = [
    "CircleFit",
    "IdentificationError",
    "IdentifiedLoop",
    "LinkAxisFit",
    "LinkRecord",
    "RecordIdentification",
    "RunStatistics",
    "bennett_ratios",
    "clean_record",
    "fit_circle",
    "fit_link_axis",
    "identify_axes",
    "identify_branch",
    "identify_dh",
    "identify_loop",
    "identify_record",
    "moving_average",
    "project_into_previous_frame",
    "read_simulation_result",
    "read_vicon_csv",
    "run_statistics",
]
