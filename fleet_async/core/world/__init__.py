"""What is in the scene: the state store, the PyBullet backend, shapes, attachments, bodies
waiting to be created in batches (``pending.py``), ``World``.

``World`` keeps objects as handles it is given; it never imports the body classes.
May import ``geometry`` and ``base``.
"""
