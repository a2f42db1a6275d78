"""
``orthoglide urdf``, ``draw`` and ``animate``: files written, and refusals.

The pictures are read back with Pillow (matplotlib's own dependency): a
valid PNG or GIF of the size asked for, the GIF with one frame per sample;
bad input exits 2 with one clear line and writes nothing. The drawn bodies
are ``bodies.elements``' (checked on the scene's lines).
"""

import struct

import numpy as np
from orthoglide_ros.model import bodies
from orthoglide_ros.tools import cli, drawing
from orthoglide_ros.model.robot import Robot
from orthoglide_ros.model.urdf import urdf
import pytest
from urdf_harness import COMMITTED_URDF

Image = pytest.importorskip('PIL.Image')

PNG_MAGIC = b'\x89PNG\r\n\x1a\n'


def run(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def png_size(data):
    """Width and height from the PNG's IHDR chunk, read by hand."""
    assert data[:8] == PNG_MAGIC and data[12:16] == b'IHDR'
    return struct.unpack('>II', data[16:24])


def assert_refused(code, out, err, *words):
    assert code == 2, err
    assert out == ''
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('orthoglide: error: '), err
    for word in words:
        assert word in lines[0], (word, lines[0])


# urdf ----------------------------------------------------------------------
def test_urdf_to_stdout_is_the_committed_file(capsys):
    code, out, err = run(capsys, 'urdf')
    assert code == 0, err
    assert out == COMMITTED_URDF.read_text()


def test_urdf_with_params_names_and_margin(capsys, tmp_path):
    params = tmp_path / 'robot.yaml'
    params.write_text('feedforward:\n  ros__parameters:\n    robot:\n'
                      '      m5: 18.0\n      l3: 0.9\n')
    path = tmp_path / 'robot.urdf'
    code, _, err = run(capsys, 'urdf', '--params', params, '--output', path,
                       '--joint-names', 'ja', 'jb', 'jc',
                       '--singularity-margin', '0.3')
    assert code == 0, err
    robot = Robot(m5=18.0, l3=0.9)
    assert path.read_text() == urdf(robot, ('ja', 'jb', 'jc'), 0.3)
    assert '<mass value="18" />' in path.read_text()


@pytest.mark.parametrize('argv, words', [
    (['--joint-names', 'a', 'a', 'b'], ['--joint-names', 'distinct']),
    (['--singularity-margin', '1.5'], ['--singularity-margin']),
])
def test_urdf_bad_input(capsys, argv, words):
    code, out, err = run(capsys, 'urdf', *argv)
    assert code == 2 and out == ''
    for word in words:
        assert word in err


# draw ----------------------------------------------------------------------
def test_draw_writes_a_png_of_the_size_asked(capsys, tmp_path):
    path = tmp_path / 'robot.png'
    code, _, err = run(capsys, 'draw', '--position', 0.05, 0.1, -0.2,
                       '--output', path, '--size', 640, 480)
    assert code == 0, err
    data = path.read_bytes()
    assert png_size(data) == (640, 480)
    with Image.open(path) as image:
        assert image.format == 'PNG' and image.size == (640, 480)
        image.load()


@pytest.mark.parametrize('argv, words', [
    (['--position', '0.9', '0', '0'], ['out of reach']),
    (['--position', 'nan', '0', '0'], ['not finite']),
    (['--position', '0.45', '0.45', '0.45'], ['singularity']),
])
def test_draw_refuses_a_bad_position(capsys, tmp_path, argv, words):
    path = tmp_path / 'robot.png'
    assert_refused(*run(capsys, 'draw', *argv, '--output', path), *words)
    assert not path.exists()


def test_draw_refuses_other_extensions_and_sizes(capsys, tmp_path):
    assert_refused(*run(capsys, 'draw', '--position', 0, 0, 0, '--output',
                        tmp_path / 'robot.jpg'), '.png')
    code, out, err = run(capsys, 'draw', '--position', 0, 0, 0, '--output',
                         tmp_path / 'r.png', '--size', 10, 10)
    assert code == 2 and 'pixels' in err
    assert not list(tmp_path.iterdir())


# animate -------------------------------------------------------------------
def test_animate_the_paper_trajectory(capsys, tmp_path):
    path = tmp_path / 'paper.gif'
    code, _, err = run(capsys, 'animate', '--output', path, '--frames', 6,
                       '--size', 320, 240)
    assert code == 0, err
    with Image.open(path) as image:
        assert image.format == 'GIF'
        assert image.size == (320, 240)
        assert image.n_frames == 6
        assert image.info.get('loop') == 0
        assert image.info['duration'] == pytest.approx(50, abs=1)  # 20 fps


def test_animate_a_csv_file_sampled_down(capsys, tmp_path):
    source = tmp_path / 'line.csv'
    rows = ['t,x,y,z'] + [f'{0.1 * k!r},{0.01 * k!r},0.0,0.0'
                          for k in range(30)]
    source.write_text('\n'.join(rows) + '\n')
    path = tmp_path / 'line.gif'
    code, _, err = run(capsys, 'animate', '--input', source, '--output',
                       path, '--frames', 4, '--fps', 10, '--size', 200, 200)
    assert code == 0, err
    with Image.open(path) as image:
        assert image.n_frames == 4 and image.size == (200, 200)
        assert image.info['duration'] == pytest.approx(100, abs=1)


@pytest.mark.parametrize('body, words', [
    ('t,x,y,z\n0,0,0,0\n1,0.9,0,0\n', ['data row 2', 'out of reach']),
    ('t,x,y\n0,0,0\n', ["'z'"]),
    ('t,x,y,z\n', ['no data row']),
])
def test_animate_refuses_bad_input(capsys, tmp_path, body, words):
    source = tmp_path / 'bad.csv'
    source.write_text(body)
    path = tmp_path / 'bad.gif'
    assert_refused(*run(capsys, 'animate', '--input', source, '--output',
                        path), *words)
    assert not path.exists()


def test_animate_refuses_other_extensions(capsys, tmp_path):
    assert_refused(*run(capsys, 'animate', '--output', tmp_path / 'a.png'),
                   '.gif')


# The scene -----------------------------------------------------------------
def test_the_drawn_bodies_are_the_models():
    robot = Robot()
    position = (0.05, 0.1, -0.2)
    scene = drawing._Scene(robot, (200, 200), 1.0)
    scene.update(position, (1.0, 2.0, 3.0), 'test')
    legs = bodies.elements(robot, position)
    for leg in 'ABC':
        for start, end, _ in drawing.SEGMENTS:
            x, y, z = scene.lines[leg, start, end].get_data_3d()
            want = np.array([legs[leg]['joints'][start],
                             legs[leg]['joints'][end]]).T
            assert np.allclose([x, y, z], want, rtol=0, atol=1e-15)
