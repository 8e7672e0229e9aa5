#!/usr/bin/env python3
"""Writes tests/malformed/calibrations/: broken image sets, one problem each.

Each case is a folder holding a calibration (NeRF `transforms.json`, or a
COLMAP `sparse/0/cameras.txt` + `images.txt` with `images/`), tiny 8x8 RGBA
PNGs, and `expect.txt`: the calibration file to give lodkit (first line)
and the text naming the camera the one-line error must contain (second
line; empty when the file as a whole is bad); a third line `carving` when
the set reads and only carving finds the fault (`lodkit info` then
succeeds). `crates/cli/tests/
malformed_calibrations.rs` runs `lodkit info`, `lodkit pop encode
--silhouettes` and `lodkit build` on each: exit 1, one line naming the
file and the camera.

Standard library only, deterministic output:

    python3 scripts/make_malformed_calibrations.py
"""
import json
import math
import os
import shutil
import struct
import zlib

ROOT = os.path.join(os.path.dirname(__file__), "..", "tests", "malformed", "calibrations")
SIZE = 8


def png(width, height, alpha):
    """RGBA8 PNG, grey, alpha 255 in the middle 4x4 block when `alpha`."""
    rows = b""
    for y in range(height):
        rows += b"\x00"
        for x in range(width):
            inside = alpha and 2 <= x < width - 2 and 2 <= y < height - 2
            rows += bytes([200, 120, 60, 255 if inside else 0])

    def chunk(kind, data):
        c = kind + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b"")


def look_at_gl(eye, target=(0.0, 0.0, 0.0)):
    """Camera-to-world 4x4, OpenGL axes (looks along -Z), +Y up."""
    back = [e - t for e, t in zip(eye, target)]
    n = math.sqrt(sum(v * v for v in back))
    back = [v / n for v in back]
    up = [0.0, 1.0, 0.0]
    right = [up[1] * back[2] - up[2] * back[1], up[2] * back[0] - up[0] * back[2], up[0] * back[1] - up[1] * back[0]]
    n = math.sqrt(sum(v * v for v in right))
    right = [v / n for v in right]
    cup = [back[1] * right[2] - back[2] * right[1], back[2] * right[0] - back[0] * right[2], back[0] * right[1] - back[1] * right[0]]
    return [
        [round(right[0], 6), round(cup[0], 6), round(back[0], 6), eye[0]],
        [round(right[1], 6), round(cup[1], 6), round(back[1], 6), eye[1]],
        [round(right[2], 6), round(cup[2], 6), round(back[2], 6), eye[2]],
        [0.0, 0.0, 0.0, 1.0],
    ]


EYES = [(0.0, 0.0, 4.0), (4.0, 0.0, 0.0), (0.0, 0.0, -4.0), (-4.0, 0.0, 0.0)]


def nerf(name, edit=None, raw=None, images=4, alpha=True, expect_camera="", carving=False, says=None):
    d = os.path.join(ROOT, name)
    os.makedirs(os.path.join(d, "images"))
    for i in range(images):
        with open(os.path.join(d, "images", f"{i:03}.png"), "wb") as f:
            f.write(png(SIZE, SIZE, alpha))
    t = {
        "camera_angle_x": 0.6,
        "w": SIZE,
        "h": SIZE,
        "frames": [
            {"file_path": f"images/{i:03}.png", "transform_matrix": look_at_gl(e)} for i, e in enumerate(EYES)
        ],
    }
    if edit:
        edit(t)
    text = raw if raw is not None else json.dumps(t, indent=1)
    with open(os.path.join(d, "transforms.json"), "w") as f:
        f.write(text)
    with open(os.path.join(d, "expect.txt"), "w") as f:
        f.write(f"transforms.json\n{expect_camera}\n" + ("carving\n" if carving else "")
                + (f"says: {says}\n" if says else ""))


def colmap(name, cameras=None, images=None, files=4, expect_camera="", carving=False, says=None):
    d = os.path.join(ROOT, name)
    os.makedirs(os.path.join(d, "images"))
    os.makedirs(os.path.join(d, "sparse", "0"))
    for i in range(files):
        with open(os.path.join(d, "images", f"{i:03}.png"), "wb") as f:
            f.write(png(SIZE, SIZE, True))
    if cameras is None:
        cameras = f"1 PINHOLE {SIZE} {SIZE} 13 13 4 4\n"
    if images is None:
        images = RING
    with open(os.path.join(d, "sparse", "0", "cameras.txt"), "w") as f:
        f.write(cameras)
    with open(os.path.join(d, "sparse", "0", "images.txt"), "w") as f:
        f.write(images)
    with open(os.path.join(d, "expect.txt"), "w") as f:
        f.write(f"sparse/0/cameras.txt\n{expect_camera}\n" + ("carving\n" if carving else "")
                + (f"says: {says}\n" if says else ""))


# World-to-camera poses (OpenCV axes) of four cameras 4 units from the
# origin looking at it: rotations of 0, 90, 180, 270 degrees about +Y,
# T = (0, 0, 4) (the origin 4 units ahead).
RING = "".join(
    f"{i + 1} {math.cos(a / 2):.7f} 0 {math.sin(a / 2):.7f} 0 0 0 4 1 {i:03}.png\n\n"
    for i, a in enumerate(k * math.pi / 2 for k in range(4))
)


def turned_round(t):
    for f in t["frames"]:
        m = f["transform_matrix"]
        for r in range(3):
            for c in (0, 2):
                m[r][c] = -m[r][c]


def main():
    if os.path.isdir(ROOT):
        shutil.rmtree(ROOT)
    os.makedirs(ROOT)
    nerf("nerf_camera_behind_every_view", turned_round, expect_camera="frame 0", carving=True)
    nerf("nerf_image_missing", lambda t: t["frames"][1].update(file_path="images/missing.png"), expect_camera="frame 1")
    nerf("nerf_size_disagrees_with_intrinsics", lambda t: t.update(w=10), expect_camera="frame 0")
    nerf("nerf_json_truncated", raw='{"camera_angle_x": 0.6, "frames": [{"file_path": "images/000.png", ')
    nerf("nerf_not_json", raw="camera_angle_x = 0.6\n")
    nerf("nerf_number_out_of_range", raw='{"camera_angle_x": 1e400, "frames": []}')
    nerf("nerf_no_frames", lambda t: t.update(frames=[]))
    nerf("nerf_matrix_scaled", lambda t: t["frames"][2]["transform_matrix"][0].__setitem__(0, 3.0), expect_camera="frame 2")
    nerf("nerf_matrix_not_4x4", lambda t: t["frames"][0].update(transform_matrix=[[1, 0, 0]]), expect_camera="frame 0")
    nerf("nerf_path_parent_dir", lambda t: t["frames"][0].update(file_path="../images/000.png"), expect_camera="frame 0")
    nerf("nerf_path_percent_parent_dir", lambda t: t["frames"][3].update(file_path="%2e%2e/images/003.png"), expect_camera="frame 3")
    nerf("nerf_path_absolute", lambda t: t["frames"][1].update(file_path="/etc/passwd"), expect_camera="frame 1")
    nerf("nerf_path_file_scheme", lambda t: t["frames"][1].update(file_path="file:///etc/passwd"), expect_camera="frame 1")
    nerf("nerf_no_focal_length", lambda t: t.pop("camera_angle_x"), expect_camera="frame 0")
    nerf("nerf_angle_out_of_range", lambda t: t.update(camera_angle_x=4.0), expect_camera="frame 0")
    nerf("nerf_no_alpha_no_mask", alpha=False, expect_camera="frame 0")
    nerf("nerf_file_path_not_a_string", lambda t: t["frames"][2].update(file_path=7), expect_camera="frame 2")
    colmap("colmap_unknown_camera_model", cameras="1 FISHEYE 8 8 13 4 4 0.1\n", expect_camera="camera 1")
    colmap("colmap_wrong_parameter_count", cameras="1 PINHOLE 8 8 13 13 4\n", expect_camera="camera 1")
    colmap("colmap_focal_not_a_number", cameras="1 SIMPLE_RADIAL 8 8 abc 4 4 0\n", expect_camera="camera 1")
    colmap("colmap_negative_focal", cameras="1 SIMPLE_PINHOLE 8 8 -13 4 4\n", expect_camera="camera 1")
    colmap("colmap_size_disagrees_with_intrinsics", cameras="1 RADIAL 16 16 13 8 8 0 0\n", expect_camera="image 1")
    colmap("colmap_image_missing", files=1, expect_camera="image 2")
    colmap("colmap_quaternion_zero", images="1 0 0 0 0 0 0 4 1 000.png\n\n", expect_camera="image 1")
    colmap("colmap_camera_not_listed", images="1 0 1 0 0 0 0 4 7 000.png\n\n", expect_camera="image 1")
    colmap("colmap_name_parent_dir", images="1 0 1 0 0 0 0 4 1 ../../images/000.png\n\n", expect_camera="image 1")
    colmap("colmap_short_pose_line", images="1 0 1 0 0 0 0\n\n", expect_camera="line 1")
    colmap(
        "colmap_camera_behind_every_view",
        images=RING.replace(" 0 0 4 1 ", " 0 0 -4 1 "),
        expect_camera="image 1",
        carving=True,
    )
    colmap("colmap_no_cameras", cameras="# nothing\n")
    # A name that is the folder itself: with `.png` added it would be the
    # folder's sibling `<folder>.png`.
    nerf("nerf_file_path_dot", lambda t: t["frames"][0].update(file_path="."), expect_camera="frame 0",
         says="names the folder itself")
    nerf("nerf_file_path_dot_slash", lambda t: t["frames"][2].update(file_path="././"), expect_camera="frame 2",
         says="names the folder itself")
    nerf("nerf_matrix_bottom_row", lambda t: t["frames"][1]["transform_matrix"].__setitem__(3, [0, 0, 1, 1]),
         expect_camera="frame 1", says="bottom row")
    # Every pixel of a run is budgeted from the calibration, before decoding.
    nerf("nerf_pixels_over_budget", lambda t: t.update(w=16384, h=16384), expect_camera="frame 0",
         says="left of the run's budget")
    # images.txt without its POINTS2D lines: every second image would be
    # skipped as one.
    colmap("colmap_no_points2d_lines", images=RING.replace("\n\n", "\n"), expect_camera="line 2",
           says="POINTS2D")


if __name__ == "__main__":
    main()
