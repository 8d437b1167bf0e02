"""A small VT100/xterm screen: enough to see what a user sees of `spindown watch` on a terminal
of a given size (cursor moves, erase, scroll, autowrap with xterm's deferred wrap).

`wraps` records every line that ran past the right edge (the terminal wrapped it)."""
import re
import unicodedata


def cell_width(ch):
    if unicodedata.combining(ch):
        return 0
    return 2 if unicodedata.east_asian_width(ch) in ("W", "F") else 1


class Screen:
    def __init__(self, cols, rows):
        self.cols, self.rows = cols, rows
        self.grid = [[" "] * cols for _ in range(rows)]
        self.x = self.y = 0
        self.pending = False
        self.wraps = []
        self.top, self.bottom = 0, rows - 1
        self.cur_line_text = ""

    def scroll(self):
        del self.grid[self.top]
        self.grid.insert(self.bottom, [" "] * self.cols)

    def newline(self):
        if self.y == self.bottom:
            self.scroll()
        elif self.y < self.rows - 1:
            self.y += 1

    def put(self, ch):
        w = cell_width(ch)
        if w == 0:
            return
        if self.pending or self.x + w > self.cols:
            self.wraps.append("".join(self.grid[self.y]).rstrip() + ch)
            self.x = 0
            self.newline()
            self.pending = False
        self.grid[self.y][self.x] = ch
        if w == 2 and self.x + 1 < self.cols:
            self.grid[self.y][self.x + 1] = ""
        self.x += w
        if self.x >= self.cols:
            self.x = self.cols - 1
            self.pending = True

    def erase_line(self, mode):
        row = self.grid[self.y]
        if mode == 0:
            rng = range(self.x, self.cols)
        elif mode == 1:
            rng = range(0, self.x + 1)
        else:
            rng = range(self.cols)
        for i in rng:
            row[i] = " "

    def erase_display(self, mode):
        if mode in (2, 3):
            self.grid = [[" "] * self.cols for _ in range(self.rows)]
            return
        if mode == 0:
            self.erase_line(0)
            for r in range(self.y + 1, self.rows):
                self.grid[r] = [" "] * self.cols
        elif mode == 1:
            self.erase_line(1)
            for r in range(0, self.y):
                self.grid[r] = [" "] * self.cols

    def csi(self, params, final, private):
        ps = [int(p) if p.isdigit() else 0 for p in params.split(";")] if params else []

        def p(i, d):
            return ps[i] if len(ps) > i and ps[i] else d
        self.pending = False if final not in "m" else self.pending
        if private:
            if final in "hl" and params in ("1049", "47", "1047"):
                self.grid = [[" "] * self.cols for _ in range(self.rows)]
                self.x = self.y = 0
            return
        if final in "Hf":
            self.y = min(self.rows - 1, max(0, p(0, 1) - 1))
            self.x = min(self.cols - 1, max(0, p(1, 1) - 1))
        elif final == "A":
            self.y = max(0, self.y - p(0, 1))
        elif final == "B":
            self.y = min(self.rows - 1, self.y + p(0, 1))
        elif final == "C":
            self.x = min(self.cols - 1, self.x + p(0, 1))
        elif final == "D":
            self.x = max(0, self.x - p(0, 1))
        elif final == "G":
            self.x = min(self.cols - 1, max(0, p(0, 1) - 1))
        elif final == "d":
            self.y = min(self.rows - 1, max(0, p(0, 1) - 1))
        elif final == "J":
            self.erase_display(ps[0] if ps else 0)
        elif final == "K":
            self.erase_line(ps[0] if ps else 0)
        elif final == "r":
            self.top = max(0, p(0, 1) - 1)
            self.bottom = min(self.rows - 1, p(1, self.rows) - 1)
            self.x = self.y = 0
        elif final == "L":
            for _ in range(p(0, 1)):
                del self.grid[self.bottom]
                self.grid.insert(self.y, [" "] * self.cols)
        elif final == "M":
            for _ in range(p(0, 1)):
                del self.grid[self.y]
                self.grid.insert(self.bottom, [" "] * self.cols)
        # m (colours), s/u and the rest: no effect on the text

    def feed(self, text):
        i, n = 0, len(text)
        csi_re = re.compile(r"\x1b\[([?>=]?)([0-9;]*)[ -/]*([@-~])")
        while i < n:
            ch = text[i]
            if ch == "\x1b":
                m = csi_re.match(text, i)
                if m:
                    self.csi(m.group(2), m.group(3), m.group(1))
                    i = m.end()
                    continue
                if text.startswith("\x1b]", i):         # OSC ... BEL or ST
                    j = text.find("\x07", i)
                    k = text.find("\x1b\\", i)
                    ends = [e for e in (j + 1 if j >= 0 else -1, k + 2 if k >= 0 else -1) if e > 0]
                    i = min(ends) if ends else n
                    continue
                if i + 1 < n and text[i + 1] == "M":       # reverse index
                    if self.y == self.top:
                        del self.grid[self.bottom]
                        self.grid.insert(self.top, [" "] * self.cols)
                    else:
                        self.y = max(0, self.y - 1)
                    i += 2
                    continue
                if i + 1 < n and text[i + 1] in "()":
                    i += 3
                    continue
                i += 2
                continue
            if ch == "\r":
                self.x = 0
                self.pending = False
            elif ch == "\n":
                self.pending = False
                self.newline()
            elif ch == "\b":
                self.x = max(0, self.x - 1)
                self.pending = False
            elif ch == "\t":
                self.x = min(self.cols - 1, (self.x // 8 + 1) * 8)
            elif ch in "\x07\x00\x0e\x0f":
                pass
            elif ord(ch) >= 32:
                self.put(ch)
            i += 1

    def lines(self):
        return ["".join(r).rstrip() for r in self.grid]
