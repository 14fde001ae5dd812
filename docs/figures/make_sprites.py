"""Draw the sprite images of ``levels/14_skinned_arm.toml``: ``python docs/figures/make_sprites.py``.

The art is made here, with Pillow, so it is the project's own and ships under its licence. Each
image is drawn at four times its size and shrunk with a Lanczos filter, for smooth edges. A link's
image lies along +x with its two joints on the middle line, ``JOINT_INSET`` px in from each end,
so the level sets ``sprite_pivot`` to the first joint and ``sprite_scale`` to world px per image
px (every image here is drawn for 0.75).
"""

from __future__ import annotations

from pathlib import Path

from PIL import Image, ImageDraw

OUT = Path(__file__).resolve().parents[2] / "assets" / "sprites"
SS = 4  # drawn at this many times the size, then shrunk
INK = (42, 34, 46, 255)
STEEL = (176, 184, 196, 255)
STEEL_DARK = (104, 112, 128, 255)


def _canvas(width: int, height: int) -> tuple[Image.Image, ImageDraw.ImageDraw]:
    image = Image.new("RGBA", (width * SS, height * SS), (0, 0, 0, 0))
    return image, ImageDraw.Draw(image)


def _save(image: Image.Image, name: str) -> None:
    size = (image.width // SS, image.height // SS)
    image.resize(size, Image.Resampling.LANCZOS).save(OUT / name, optimize=True)


def _bolt(draw: ImageDraw.ImageDraw, x: float, y: float, r: float) -> None:
    s = SS
    draw.ellipse((s * (x - r), s * (y - r), s * (x + r), s * (y + r)), fill=INK)
    r2 = r - 3
    draw.ellipse((s * (x - r2), s * (y - r2), s * (x + r2), s * (y + r2)), fill=STEEL)
    r3 = r2 * 0.4
    draw.ellipse((s * (x - r3), s * (y - r3), s * (x + r3), s * (y + r3)), fill=STEEL_DARK)


def arm_segment(name: str, width: int, height: int, inset: int, color: tuple, light: tuple) -> None:
    """A plated arm segment: a rounded bar, a highlight, a bolt on each joint."""
    image, draw = _canvas(width, height)
    s, pad = SS, 3
    box = (pad * s, pad * s, (width - pad) * s, (height - pad) * s)
    radius = (height / 2 - pad) * s
    draw.rounded_rectangle(box, radius=radius, fill=INK)
    inner = (box[0] + 3 * s, box[1] + 3 * s, box[2] - 3 * s, box[3] - 3 * s)
    draw.rounded_rectangle(inner, radius=radius - 3 * s, fill=color)
    band = (inset * s, (height * 0.28) * s, (width - inset) * s, (height * 0.40) * s)
    draw.rounded_rectangle(band, radius=(height * 0.06) * s, fill=light)
    # Rivets along the plate, between the joints.
    for k in range(1, 4):
        x = inset + (width - 2 * inset) * k / 4
        y = height * 0.70
        draw.ellipse(((x - 2.5) * s, (y - 2.5) * s, (x + 2.5) * s, (y + 2.5) * s), fill=INK)
    joint_r = height * 0.30
    _bolt(draw, inset, height / 2, joint_r)
    _bolt(draw, width - inset, height / 2, joint_r)
    _save(image, name)


def claw(name: str = "claw.png") -> None:
    """The hand: a wrist on the joint and two fingers around the tip (x = 120 px)."""
    width, height = 160, 96
    image, draw = _canvas(width, height)
    s, cy = SS, height / 2
    finger = [(70, 6), (112, 30), (140, 22), (128, 12), (106, 16), (86, 4)]  # (x, out from cy)
    for sign in (-1, 1):
        outer = [(x, cy + sign * dy) for x, dy in finger]
        draw.polygon([(x * s, y * s) for x, y in outer], fill=INK)
        # The steel face: the same finger shrunk toward its middle, leaving an ink rim.
        mx, my = sum(x for x, _ in outer) / 6, sum(y for _, y in outer) / 6
        face = [(mx + (x - mx) * 0.78, my + (y - my) * 0.62) for x, y in outer]
        draw.polygon([(x * s, y * s) for x, y in face], fill=STEEL)
    draw.rounded_rectangle((6 * s, (cy - 20) * s, 92 * s, (cy + 20) * s), radius=20 * s, fill=INK)
    draw.rounded_rectangle(
        (10 * s, (cy - 16) * s, 88 * s, (cy + 16) * s), radius=16 * s, fill=(232, 84, 72, 255)
    )
    draw.rounded_rectangle(
        (30 * s, (cy - 11) * s, 82 * s, (cy - 6) * s), radius=2 * s, fill=(246, 150, 130, 255)
    )
    _bolt(draw, 24, cy, 14)
    # The tip the level aims: a small lamp between the fingers.
    draw.ellipse((114 * s, (cy - 6) * s, 126 * s, (cy + 6) * s), fill=INK)
    draw.ellipse((116 * s, (cy - 4) * s, 124 * s, (cy + 4) * s), fill=(255, 214, 90, 255))
    _save(image, name)


def ball(name: str = "ball.png") -> None:
    """A beach ball: six coloured wedges, so its turning shows."""
    size = 96
    image, draw = _canvas(size, size)
    s = SS
    box = (2 * s, 2 * s, (size - 2) * s, (size - 2) * s)
    draw.ellipse(box, fill=INK)
    inner = (5 * s, 5 * s, (size - 5) * s, (size - 5) * s)
    colors = [(240, 84, 72), (255, 255, 255), (60, 150, 230), (255, 255, 255), (250, 196, 60)]
    colors.append((255, 255, 255))
    for k, color in enumerate(colors):
        draw.pieslice(inner, 60 * k, 60 * (k + 1), fill=(*color, 255))
    c = size / 2
    draw.ellipse(((c - 9) * s, (c - 9) * s, (c + 9) * s, (c + 9) * s), fill=INK)
    draw.ellipse(((c - 6) * s, (c - 6) * s, (c + 6) * s, (c + 6) * s), fill=(255, 255, 255, 255))
    _save(image, name)


def crate(name: str = "crate.png") -> None:
    """A wooden crate: planks, a frame and a cross brace."""
    size = 96
    image, draw = _canvas(size, size)
    s = SS
    wood, dark, light = (196, 132, 72, 255), (120, 74, 36, 255), (222, 170, 110, 255)
    draw.rectangle((0, 0, size * s - 1, size * s - 1), fill=INK)
    draw.rectangle((4 * s, 4 * s, (size - 4) * s, (size - 4) * s), fill=wood)
    for y in range(22, size - 8, 18):
        draw.line((4 * s, y * s, (size - 4) * s, y * s), fill=dark, width=2 * s)
    draw.rectangle((4 * s, 4 * s, (size - 4) * s, (size - 4) * s), outline=dark, width=10 * s)
    draw.line((12 * s, 12 * s, (size - 12) * s, (size - 12) * s), fill=dark, width=12 * s)
    draw.line((12 * s, 12 * s, (size - 12) * s, (size - 12) * s), fill=light, width=6 * s)
    _save(image, name)


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    arm_segment("upper_arm.png", 256, 64, 32, (240, 138, 36, 255), (252, 196, 120, 255))
    arm_segment("forearm.png", 224, 56, 28, (46, 170, 160, 255), (140, 222, 210, 255))
    claw()
    ball()
    crate()


if __name__ == "__main__":
    main()
