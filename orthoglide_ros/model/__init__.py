"""
The model: the Orthoglide's mechanics, plain numpy, no ROS.

:mod:`robot` (the validated description), :mod:`kernel` (the paper's
recursion as one scalar/array kernel), :mod:`mechanics` (inverse and
forward kinematics and dynamics, workspace), :mod:`plant` (RK4 and the
simulated robot), :mod:`trajectory` (eq. 6, the excitation),
:mod:`joint_plan` (a joint trajectory sampled as
joint_trajectory_controller does) and :mod:`urdf` (the robot as a URDF).
Nothing here imports rclpy or any other sub-package but this one.
"""
