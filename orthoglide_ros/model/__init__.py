"""
The model: the Orthoglide's mechanics, plain numpy, no ROS.

Nothing here imports rclpy or any other sub-package of the package
(doc/model.md, doc/mechanics.md).
"""
