"""Build script for the orthoglide_ros ament_python package."""

from glob import glob

import setuptools
from setuptools import setup

package_name = 'orthoglide_ros'
test_requires = ['pytest', 'hypothesis']

# setuptools < 72 (e.g. Ubuntu 24.04's, used by apt ROS Jazzy) still knows
# tests_require; newer ones warn "Unknown distribution option".
legacy_kwargs = {}
if int(setuptools.__version__.split('.')[0]) < 72:
    legacy_kwargs['tests_require'] = test_requires

setup(
    name=package_name,
    version='0.1.0',
    # The layers: model, formats, cores, ros (the glue), tools.
    packages=setuptools.find_packages(include=[package_name,
                                               package_name + '.*']),
    data_files=[
        ('share/ament_index/resource_index/packages',
            ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        # config/orthoglide.yaml, the Fast DDS profile and the RViz config
        # (any config/*.yaml, config/*.xml and config/*.rviz).
        ('share/' + package_name + '/config',
            sorted(glob('config/*.yaml') + glob('config/*.xml')
                   + glob('config/*.rviz'))),
        # The robot's URDF (urdf/orthoglide.urdf, written by `orthoglide
        # urdf` for the paper's robot).
        ('share/' + package_name + '/urdf', sorted(glob('urdf/*.urdf'))),
        # The robot's MJCF (mjcf/orthoglide.xml, written by `orthoglide
        # mjcf` for the paper's robot), for MuJoCo.
        ('share/' + package_name + '/mjcf', sorted(glob('mjcf/*.xml'))),
    ],
    # ROS packages (rclpy, *_msgs) are deliberately absent: they come from
    # apt ROS or from the ros-jazzy-* wheels in requirements.txt. scipy and
    # rosbags (orthoglide identify) are plain PyPI libraries, as numpy.
    install_requires=['setuptools', 'numpy', 'PyYAML', 'scipy', 'rosbags>=0.11'],
    zip_safe=True,
    maintainer='Orthoglide ROS maintainers',
    maintainer_email='orthoglide@example.com',
    description='ROS 2 nodes and tools for the Orthoglide parallel robot.',
    license='Apache-2.0',
    # With newer setuptools colcon only runs pytest if it is declared here.
    extras_require={
        'test': test_requires,
    },
    entry_points={
        'console_scripts': [
            # The nodes start through console.py: signals are taken over
            # before anything heavy is imported.
            'feedforward = orthoglide_ros.ros.console:feedforward',
            'orthoglide = orthoglide_ros.tools.cli:main',
            'setpoint_publisher = orthoglide_ros.ros.console:setpoint_publisher',
            'tracking_controller = orthoglide_ros.ros.console:tracking_controller',
            'simulator = orthoglide_ros.ros.console:simulator',
            'mechanism_state_publisher = '
            'orthoglide_ros.ros.console:mechanism_state_publisher',
            'planner = orthoglide_ros.ros.console:planner',
        ],
    },
    **legacy_kwargs,
)
