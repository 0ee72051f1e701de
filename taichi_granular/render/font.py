"""A 3x5 pixel bitmap font for frame annotations (time stamp, colour-bar labels), drawn with
numpy so that frames need no font files and no display. Lower-case letters, digits and the
few symbols numbers and units need; anything else draws as a blank."""
import numpy as np

_GLYPHS = {
    "0": "111101101101111", "1": "010110010010111", "2": "111001111100111", "3": "111001111001111",
    "4": "101101111001001", "5": "111100111001111", "6": "111100111101111", "7": "111001010010010",
    "8": "111101111101111", "9": "111101111001111", ".": "000000000000010", "-": "000000111000000",
    "+": "000010111010000", "=": "000111000111000", "/": "001001010100100", "_": "000000000000111",
    ":": "000010000010000", "(": "010100100100010", ")": "010001001001010", "^": "010101000000000",
    "a": "000011101101011", "b": "100110101101110", "c": "000011100100011", "d": "001011101101011",
    "e": "000111111100011", "f": "011100110100100", "g": "011101011001110", "h": "100110101101101",
    "i": "010000010010010", "j": "001000001101010", "k": "100101110101101", "l": "110010010010111",
    "m": "000111111101101", "n": "000110101101101", "o": "000010101101010", "p": "000110101110100",
    "q": "000011101011001", "r": "000101110100100", "s": "000011110011110", "t": "010111010010011",
    "u": "000101101101011", "v": "000101101101010", "w": "000101101111111", "x": "000101010101101",
    "y": "000101011001110", "z": "000111011110111", " ": "000000000000000",
}
GLYPH_WIDTH, GLYPH_HEIGHT = 3, 5


def text_width(text: str, scale: int) -> int:
    return len(text) * (GLYPH_WIDTH + 1) * scale


def draw_text(image: np.ndarray, text: str, left: int, top: int, scale: int = 2,
              colour=(0.0, 0.0, 0.0)) -> None:
    """Draw ``text`` into ``image`` (rows top-down, shape (H, W, 3), floats) in place."""
    for k, char in enumerate(text.lower()):
        bits = _GLYPHS.get(char, _GLYPHS[" "])
        glyph = np.array([int(b) for b in bits], bool).reshape(GLYPH_HEIGHT, GLYPH_WIDTH)
        glyph = np.kron(glyph, np.ones((scale, scale), bool))
        x0 = left + k * (GLYPH_WIDTH + 1) * scale
        rows = slice(max(top, 0), min(top + glyph.shape[0], image.shape[0]))
        cols = slice(max(x0, 0), min(x0 + glyph.shape[1], image.shape[1]))
        sub = glyph[rows.start - top:rows.stop - top, cols.start - x0:cols.stop - x0]
        image[rows, cols][sub] = colour
