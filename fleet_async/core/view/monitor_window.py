"""The monitor window process: reads JSON lines on stdin and shows them in a tkinter window.

Run by :class:`fleet_async.core.view.monitor.DataMonitor`; arguments: title width height x y.
"""

from __future__ import annotations

import json
import queue
import sys
import threading


def main(argv: list[str]) -> int:
    """Show the window until stdin closes or the window is closed."""
    import tkinter as tk  # imported here: only this process needs a display

    title, width, height, x, y = argv[0], int(argv[1]), int(argv[2]), int(argv[3]), int(argv[4])
    root = tk.Tk()
    root.title(title)
    geometry = f"{width}x{height}" + (f"+{x}+{y}" if x >= 0 and y >= 0 else "")
    root.geometry(geometry)
    text = tk.StringVar(value="waiting for data...")
    tk.Label(root, textvariable=text, justify="left", anchor="nw", font=("Courier", 10)).pack(
        fill="both", expand=True, padx=6, pady=6
    )
    lines: queue.Queue[str | None] = queue.Queue()

    def reader() -> None:
        for line in sys.stdin:
            lines.put(line)
        lines.put(None)

    threading.Thread(target=reader, daemon=True).start()

    def poll() -> None:
        try:
            while True:
                line = lines.get_nowait()
                if line is None:
                    root.destroy()
                    return
                data = json.loads(line)
                text.set(
                    "\n".join(
                        f"{k}: {v:.3f}" if isinstance(v, float) else f"{k}: {v}"
                        for k, v in data.items()
                    )
                )
        except queue.Empty:
            pass
        root.after(100, poll)

    root.after(100, poll)
    root.mainloop()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
