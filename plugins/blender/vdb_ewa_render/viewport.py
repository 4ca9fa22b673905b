"""The 3D view's Rendered shading: vdb_ewa images of the view, rendered on a thread of their own
while Blender's UI runs, a coarse image first, then the refined one (docs/blender.md#the-rendered-viewport).

A Session belongs to one engine instance (one 3D view). Its thread keeps a vdb_ewa.Scene per
render input (so the light maps stay between views) and renders the newest request; a newer
request cancels the running render at once (vdb_ewa.CancelToken). Images reach the main thread
through the session's lock; a timer on the main thread (bpy.app.timers) asks for the redraws.
Nothing here touches bpy from the rendering thread."""
import threading
import time
import traceback

import bpy
import gpu
import numpy as np
from gpu_extras.presets import draw_texture_2d

# Every viewport image drawn, oldest first, as dict(width, height, quality, coarse, requested,
# ready, drawn, seconds, maps_reused, rays_reused, rays_marched, line): times are time.monotonic();
# the tests read it. The newest MAX_RECORDS are kept.
RECORDS = []
MAX_RECORDS = 1000

# The keywords a vdb_ewa.Scene takes when it is made and refuses per render (SceneCall::render,
# python/render_call.cpp).
GRID_KEYWORDS = ("name", "density_grid", "color", "emission_grid", "temperature", "velocity_grid")

# How often the main thread looks for a new image to draw, in seconds.
POLL_SECONDS = 0.01

_SESSIONS = set()


def split_grid_keywords(options):
    """@a options as (the grid keywords, for the Scene's constructor; the others, per render)."""
    return ({k: v for k, v in options.items() if k in GRID_KEYWORDS},
            {k: v for k, v in options.items() if k not in GRID_KEYWORDS})


class Image:
    """A viewport image: premultiplied RGBA floats, rows bottom to top (OpenGL's), what it is and
    when it was asked for (time.monotonic()); its texture is made on the main thread when first drawn."""

    def __init__(self, pixels, quality, coarse, requested, maps_reused, rays_reused, rays_marched):
        self.pixels = pixels
        self.height, self.width = pixels.shape[:2]
        self.quality = quality
        self.coarse = coarse
        self.requested = requested
        self.ready = time.monotonic()
        self.maps_reused = maps_reused
        self.rays_reused = rays_reused
        self.rays_marched = rays_marched
        self.texture = None
        self.recorded = False

    def draw(self, engine, scene, width, height):
        """Draw it over the region (@a width x @a height pixels), premultiplied, through Blender's
        display space shader (the scene's view transform, as for F12)."""
        if self.texture is None:
            data = gpu.types.Buffer('FLOAT', self.pixels.size, self.pixels.reshape(-1))
            self.texture = gpu.types.GPUTexture((self.width, self.height), format='RGBA16F', data=data)
        gpu.state.blend_set('ALPHA_PREMULT')
        engine.bind_display_space_shader(scene)
        draw_texture_2d(self.texture, (0, 0), width, height)
        engine.unbind_display_space_shader()
        gpu.state.blend_set('NONE')

    def record(self):
        """The console line and a RECORDS entry, when first drawn."""
        if self.recorded:
            return
        self.recorded = True
        drawn = time.monotonic()
        seconds = drawn - self.requested
        line = "vdb_ewa viewport: %dx%d %s in %.3f s (reused: %d light maps, %d light rays)" % (
            self.width, self.height, self.quality, seconds, self.maps_reused, self.rays_reused)
        RECORDS.append(dict(width=self.width, height=self.height, quality=self.quality, coarse=self.coarse,
                            requested=self.requested, ready=self.ready, drawn=drawn, seconds=seconds,
                            maps_reused=self.maps_reused, rays_reused=self.rays_reused, rays_marched=self.rays_marched,
                            line=line))
        del RECORDS[:-MAX_RECORDS]
        print(line, flush=True)


class Request:
    """A render to make: the per-render keywords, the scene generation they apply to, the eye
    (to order several inputs) and when the view change asked for it."""

    def __init__(self, options, generation, eye):
        self.options = options
        self.generation = generation
        self.eye = eye
        self.requested = time.monotonic()


class Session:
    """One 3D view's renders on a thread of their own (above). The main thread calls set_scene(),
    request(), take() and stop(); the thread builds the scenes and renders."""

    def __init__(self, vdb_ewa, composite):
        """@a composite(front, back): premultiplied over, to stack several inputs nearest first."""
        self._vdb_ewa = vdb_ewa
        self._composite = composite
        self._lock = threading.Condition()
        self._generation = 0
        self._build = (0, None)  # (generation, () -> [(centre, vdb_ewa.Scene)], called on the thread)
        self._request = None
        self._token = None
        self._stopped = False
        self._image = None
        self._error = None
        self.changed = False  # a new image or error to draw (the timer asks for a redraw)
        self._thread = threading.Thread(target=self._run, name="vdb_ewa viewport", daemon=True)
        self._thread.start()
        _SESSIONS.add(self)
        if not bpy.app.timers.is_registered(_poll):
            bpy.app.timers.register(_poll, first_interval=POLL_SECONDS, persistent=True)

    # The main thread's side.
    def set_scene(self, build):
        """The volumes changed: the next render builds its scenes anew with @a build."""
        with self._lock:
            self._generation += 1
            self._build = (self._generation, build)

    def request(self, options, eye):
        """Render @a options (per-render keywords) of the current scene, unless that is what was
        last asked; a render of an older request is cancelled at once."""
        with self._lock:
            last = self._request
            if last is not None and last.generation == self._generation and last.options == options:
                return
            self._request = Request(options, self._generation, eye)
            if self._token is not None:
                self._token.cancel()
            self._lock.notify()

    def take(self):
        """(the newest image or None, the error or None), and clears `changed`."""
        with self._lock:
            self.changed = False
            return self._image, self._error

    def stop(self):
        """Cancel and end the thread (it exits once its render returns, without being waited for)."""
        with self._lock:
            self._stopped = True
            if self._token is not None:
                self._token.cancel()
            self._lock.notify()
        _SESSIONS.discard(self)

    # The rendering thread's side.
    def _run(self):
        built, scenes, done = None, [], None
        while True:
            with self._lock:
                while not self._stopped and (self._request is None or self._request is done):
                    self._lock.wait()
                if self._stopped:
                    return
                request, (generation, build) = self._request, self._build
                token = self._token = self._vdb_ewa.CancelToken()
            try:
                if generation != built:
                    scenes, built = [], None  # let the old scenes go first
                    scenes, built = build(), generation
                self._render(request, scenes, token)
            except self._vdb_ewa.Cancelled:
                pass  # a newer request waits, or the session stopped
            except Exception as e:  # shown in the view; the thread lives on for the next request
                if not isinstance(e, (self._vdb_ewa.Error, ValueError)):
                    traceback.print_exc()  # a bug of the add-on's: once per request
                with self._lock:
                    if request is self._request:
                        self._error, self._image, self.changed = str(e), None, True
            done = request

    def _render(self, request, scenes, token):
        """Render every input of @a request, nearest first, and post the composite when each has
        an image: coarse while any is coarse (once), then the refined one."""
        eye = np.asarray(request.eye)
        order = sorted(scenes, key=lambda cs: float(np.linalg.norm(np.asarray(cs[0]) - eye)))
        layers = [None] * len(order)
        posted_coarse = []

        def on_frame(frame, index):
            layers[index] = frame
            if token.cancelled or any(layer is None for layer in layers):
                return None
            coarse = any(layer.coarse for layer in layers)
            if coarse and posted_coarse:
                return None
            posted_coarse.append(coarse)
            self._post(request, layers, coarse)
            return None

        for index, (_, scene) in enumerate(order):
            scene.render(cancel=token, progressive=lambda frame, index=index: on_frame(frame, index), **request.options)

    def _post(self, request, layers, coarse):
        image = layers[0].beauty
        for layer in layers[1:]:
            image = self._composite(image, layer.beauty)
        pixels = np.ascontiguousarray(image[::-1], dtype=np.float32)  # OpenGL's rows run bottom to top
        if coarse:
            quality = "draft/%d" % max(layer.stats["coarse_scale"] for layer in layers)
        else:
            quality = str(request.options.get("quality", "default"))
        result = Image(pixels, quality, coarse, request.requested,
                       sum(layer.stats["light_maps_reused"] for layer in layers),
                       sum(layer.stats["light_rays_reused"] for layer in layers),
                       sum(layer.stats["light_rays_marched"] for layer in layers))
        with self._lock:
            if request is self._request:
                self._image, self._error, self.changed = result, None, True


# The 3D views' shadings the engine draws: Rendered, and Material Preview too (the engine's
# bl_use_eevee_viewport is False, so Blender does not give that one to EEVEE).
DRAWN_SHADINGS = ('RENDERED', 'MATERIAL')


def _poll():
    """The main thread's timer: a redraw of the 3D views the engine draws where a session has a new image."""
    if any(session.changed for session in list(_SESSIONS)):
        for window in bpy.context.window_manager.windows:
            for area in window.screen.areas:
                if area.type == 'VIEW_3D' and area.spaces.active.shading.type in DRAWN_SHADINGS:
                    area.tag_redraw()
    return POLL_SECONDS if _SESSIONS else None


def stop_all():
    """End every session (the add-on is unregistered)."""
    for session in list(_SESSIONS):
        session.stop()
