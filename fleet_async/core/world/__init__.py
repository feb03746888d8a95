"""What is in the scene: the state store, the PyBullet backend, shapes, attachments, ``World``.

``World`` keeps objects as handles it is given; it never imports the body classes.
May import ``geometry`` and ``base``.
"""
