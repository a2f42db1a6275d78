"""
Pictures of the robot from MuJoCo's offscreen renderer (``orthoglide render``).

The robot's MJCF (:mod:`orthoglide_ros.model.mjcf`) posed by the closed
form at each platform position, a fixed camera, OpenGL through EGL
(``MUJOCO_GL`` chooses another): a PNG, or a GIF along a trajectory.
:class:`RenderError`: no OpenGL backend, or MuJoCo missing. See
doc/cli.md#render.
"""

import io
import os

from orthoglide_ros.model import mechanics, mjcf

# The camera: at the workspace's centre, from the front-right, above.
LOOKAT = (-0.3, -0.3, -0.45)
DISTANCE_PER_LENGTH = 3.0   # distance / the longest bars' length
AZIMUTH, ELEVATION = 225.0, -25.0     # degrees


class RenderError(RuntimeError):
    """MuJoCo cannot render here (no OpenGL backend, or no MuJoCo)."""


def _import_mujoco():
    os.environ.setdefault('MUJOCO_GL', 'egl')
    try:
        import mujoco
    except ModuleNotFoundError as error:
        raise RenderError(f'the mujoco package is not installed: {error}') \
            from None
    except Exception as error:  # MuJoCo loads the backend as it imports
        raise _no_backend(error) from None
    return mujoco


def _no_backend(error):
    return RenderError(
        'no OpenGL backend for MuJoCo\'s offscreen renderer '
        f'(MUJOCO_GL={os.environ.get("MUJOCO_GL")}; egl needs libEGL with a '
        f'GPU or Mesa, osmesa libOSMesa): {type(error).__name__}: '
        f'{str(error).splitlines()[0] if str(error) else ""}')


class Renderer:
    """
    Renders ``robot`` at platform positions, ``size`` (width, height) px.

    Raises :class:`RenderError` when MuJoCo has no OpenGL context here,
    :class:`mechanics.WorkspaceError` for a position out of reach.
    """

    def __init__(self, robot, size=(800, 600)):
        mujoco = self._mujoco = _import_mujoco()
        self.robot = robot
        text = mjcf.mjcf(robot)
        width, height = size
        # The offscreen buffer must hold the picture.
        text = text.replace('<compiler ', '<visual><global offwidth="'
                            f'{width}" offheight="{height}" /></visual>\n'
                            '  <compiler ', 1)
        self.model = mujoco.MjModel.from_xml_string(text)
        self.data = mujoco.MjData(self.model)
        try:
            self._renderer = mujoco.Renderer(self.model, height, width)
        except Exception as error:  # each backend fails its own way
            raise _no_backend(error) from None
        self.camera = mujoco.MjvCamera()
        self.camera.lookat[:] = LOOKAT
        self.camera.distance = DISTANCE_PER_LENGTH * max(
            leg.length for leg in robot.legs)
        self.camera.azimuth, self.camera.elevation = AZIMUTH, ELEVATION

    def image(self, position):
        """Return the RGB picture (H, W, 3 uint8) at a platform position (m)."""
        mechanics.solve(self.robot, position)
        for name, (q, _, _) in mjcf.joint_values(self.robot,
                                                 position).items():
            self.data.joint(name).qpos = q
        self._mujoco.mj_forward(self.model, self.data)
        self._renderer.update_scene(self.data, self.camera)
        return self._renderer.render()

    def png(self, position):
        """Return the picture at a platform position as PNG bytes."""
        from PIL import Image
        buffer = io.BytesIO()
        Image.fromarray(self.image(position)).save(buffer, format='PNG')
        return buffer.getvalue()

    def gif(self, positions, fps):
        """Return an animated GIF of the robot at ``positions`` (m, N x 3)."""
        from PIL import Image
        frames = [Image.fromarray(self.image(p)) for p in positions]
        buffer = io.BytesIO()
        frames[0].save(buffer, format='GIF', save_all=True,
                       append_images=frames[1:], loop=0,
                       duration=round(1000.0 / fps))
        return buffer.getvalue()

    def close(self):
        """Release the OpenGL context."""
        self._renderer.close()
