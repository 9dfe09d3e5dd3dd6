"""Headless controllers: what a tab of egtviz does, without a browser.

One controller per kind of tab: the workbench (:mod:`.workbench`), the lesson (:mod:`.lesson`), the servo demo
(:mod:`.servo`), the class member, student or instructor (:mod:`.class_member`). Each owns its state (a scene model, a lesson run, a simulation and its playback), takes typed
intents (``set_field(camera, field, text)``, ``drag_camera(name, pose)``, ``check(task, text)``, ...) and exposes
typed state that the viewer draws. No controller imports viser or the viewer: the viewer maps widgets to intents
and draws state, and tests drive the controllers directly.

Layer 3 and a half: below :mod:`egtviz.viewer`, above :mod:`egtviz.scene`, :mod:`egtviz.lessons`,
:mod:`egtviz.servo` and :mod:`egtviz.classroom`. Import a controller from its module.
"""
