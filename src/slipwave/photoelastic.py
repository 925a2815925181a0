"""The photoelastic image of a slab: isochromatic fringes seen by a camera.

A dark-field circular polariscope shows ``I = I0 sin^2(pi N_f)`` with the fringe
order ``N_f = (s1 - s2) w / f_sigma``. :class:`Photoelastic` computes the
in-plane stresses of the slab at the pixel centres from the contact
displacements of a solver step (the slab's field follows linearly from them)
and renders frames as the camera (:class:`Camera`) records them: background, the
flat under the slab, optical blur, sensor noise, quantisation, and a sync LED in a
corner. The simulate stage renders a fitted test's kymograph with it; the virtual
bench its videos (:mod:`slipwave.bench.camera` writes them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import ndimage

from slipwave.solver.slab import Slab, displacement_recovery

LED_PIXELS = (slice(3, 9), slice(3, 9))
"""The sync LED's patch of a frame (rows, columns)."""


@dataclass(frozen=True)
class Camera:
    """Camera and polariscope settings.

    Attributes
    ----------
    width, height
        Image size (px).
    fps
        Nominal frame rate (frames per second of the camera's clock).
    fringe_value
        Material fringe value f_sigma (N/mm per fringe).
    intensity
        I0, the brightest fringe, in grey levels of an 8-bit image.
    background
        Grey level of the dark field (around the slab).
    flat
        Grey level of the flat seen below the interface.
    blur
        Gaussian optical blur, standard deviation in pixels.
    noise
        Sensor noise, standard deviation in 8-bit grey levels.
    bits
        8 or 16 bits per pixel.
    clock_offset
        Acquisition time (s) at which the camera's clock reads zero.
    clock_rate_error
        Relative rate error of the camera's clock (acquisition time elapses
        ``1 + clock_rate_error`` times faster than the camera counts).
    """

    width: int = 320
    height: int = 160
    fps: float = 25.0
    fringe_value: float = 0.2
    intensity: float = 210.0
    background: float = 14.0
    flat: float = 60.0
    blur: float = 0.8
    noise: float = 1.5
    bits: Literal[8, 16] = 8
    clock_offset: float = 0.0
    clock_rate_error: float = 0.0

    def acquisition_time(self, camera_time: np.ndarray) -> np.ndarray:
        """Acquisition-card time of frames stamped ``camera_time`` by the camera.

        Parameters
        ----------
        camera_time
            Frame timestamps, s.

        Returns
        -------
        numpy.ndarray
            The card's times, s.

        """
        return self.clock_offset + camera_time * (1.0 + self.clock_rate_error)


class Photoelastic:
    """Stress and fringe images of a slab on the camera's pixel grid.

    Parameters
    ----------
    slab
        The slab the solver ran.
    camera
        The camera.
    below
        Image only the slab's pixels within this height of the interface, mm, and the
        flat's just under it: a film of the band a kymograph reads, computed from the
        mesh's rows there alone, blurred and noised in those rows alone (the rest of the
        frame is the bare background). ``None``: the whole slab.
    """

    def __init__(self, slab: Slab, camera: Camera, *, below: float | None = None) -> None:
        self.slab = slab
        self.camera = camera
        recovery = displacement_recovery(slab)
        # the mesh's rows up to two beyond the height imaged: the stresses averaged to the
        # nodes the pixels use are then the whole mesh's
        kept = recovery.y.size if below is None else min(
            int(np.searchsorted(recovery.y, below)) + 3, recovery.y.size)
        self.grid_x, self.grid_y = recovery.x, recovery.y[:kept]
        n_rows, n_columns = kept, recovery.ux.shape[1]
        self._ux = recovery.ux[:kept].reshape(n_rows * n_columns, -1)
        self._uy = recovery.uy[:kept].reshape(n_rows * n_columns, -1)
        self._shape = (n_rows, n_columns)
        nu = slab.poisson_ratio
        E = slab.youngs_modulus
        self._lam = E * nu / ((1 + nu) * (1 - 2 * nu))
        self._mu = E / (2 * (1 + nu))

        # The slab fills most of the image; the flat shows as a band below it.
        band = max(4, camera.height // 8)
        margin = 6
        self.scale = min((camera.width - 2 * margin) / slab.length,
                         (camera.height - band - margin) / slab.height)
        self.interface_row = camera.height - band  # first row of the flat
        self.left_column = 0.5 * (camera.width - self.scale * slab.length)
        columns = np.arange(camera.width) + 0.5
        rows = np.arange(camera.height) + 0.5
        x = (columns - self.left_column) / self.scale - slab.length / 2
        y = (self.interface_row - rows) / self.scale
        X, Y = np.meshgrid(x, y)
        self.inside = (np.abs(X) < slab.length / 2) & (Y > 0) & (slab.height > Y)
        if below is not None:
            self.inside &= below >= Y
        # the rows rendered: with a band, those within the blur's reach of its pixels (the
        # Gaussian filter's radius and one more), whose values are then the whole frame's
        reach = int(4.0 * camera.blur + 0.5) + 1
        imaged = np.flatnonzero(self.inside.any(axis=1))
        self.rows = (slice(0, camera.height) if below is None or imaged.size == 0 else
                     slice(max(int(imaged[0]) - reach, 0),
                           min(self.interface_row + reach, camera.height)))
        px, py = X[self.inside], Y[self.inside]
        ex = np.clip(np.searchsorted(self.grid_x, px) - 1, 0, self.grid_x.size - 2)
        ey = np.clip(np.searchsorted(self.grid_y, py) - 1, 0, self.grid_y.size - 2)
        self._hx = self.grid_x[ex + 1] - self.grid_x[ex]
        self._hy = self.grid_y[ey + 1] - self.grid_y[ey]
        self._xi = (px - self.grid_x[ex]) / self._hx
        self._eta = (py - self.grid_y[ey]) / self._hy
        self._corners = [(ey + b) * n_columns + (ex + a) for b in (0, 1) for a in (0, 1)]
        self.pixel_x = px

    def stress(self, u: np.ndarray) -> np.ndarray:
        """(3, pixels): sxx, syy, sxy (MPa) in the slab for contact displacements ``u``.

        ``u`` is the solver's ``[ux, uy]`` of the contact nodes (mm). Stresses
        are taken at the element centres, averaged to the nodes and
        interpolated to the pixels: bilinear elements have strains that jump
        between elements, which would draw the mesh into the fringes.

        Parameters
        ----------
        u
            Contact displacements ``[ux, uy]``, mm.

        Returns
        -------
        numpy.ndarray
            (3, pixels) stresses, MPa.

        """
        return self.stresses(np.asarray(u)[None, :])[0]

    def stresses(self, displacements: np.ndarray) -> np.ndarray:
        """:meth:`stress` of many frames at once (a film's: one product, no loop).

        Parameters
        ----------
        displacements
            (frames, contact nodes x 2): each frame's ``[ux, uy]``, mm.

        Returns
        -------
        numpy.ndarray
            (frames, 3, pixels) stresses, MPa.

        """
        frames = displacements.shape[0]
        UX = (displacements @ self._ux.T).reshape(frames, *self._shape)
        UY = (displacements @ self._uy.T).reshape(frames, *self._shape)
        hx = np.diff(self.grid_x)[None, None, :]
        hy = np.diff(self.grid_y)[None, :, None]

        def gradient(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            d_dx = (F[:, :-1, 1:] - F[:, :-1, :-1] + F[:, 1:, 1:] - F[:, 1:, :-1]) / (2 * hx)
            d_dy = (F[:, 1:, :-1] - F[:, :-1, :-1] + F[:, 1:, 1:] - F[:, :-1, 1:]) / (2 * hy)
            return d_dx, d_dy

        dux_dx, dux_dy = gradient(UX)
        duy_dx, duy_dy = gradient(UY)
        trace = self._lam * (dux_dx + duy_dy)
        centres = np.stack([trace + 2 * self._mu * dux_dx, trace + 2 * self._mu * duy_dy,
                            self._mu * (dux_dy + duy_dx)], axis=1)
        # Average the (up to four) elements around each node.
        total = np.zeros((frames, 3, *self._shape))
        count = np.zeros(self._shape)
        for dy in (0, 1):
            for dx in (0, 1):
                rows = slice(dy, dy + centres.shape[2])
                columns = slice(dx, dx + centres.shape[3])
                total[:, :, rows, columns] += centres
                count[rows, columns] += 1
        nodal = (total / count).reshape(frames, 3, -1)
        c00, c10, c01, c11 = self._corners
        xi, eta = self._xi, self._eta
        return ((1 - xi) * (1 - eta) * nodal[:, :, c00] + xi * (1 - eta) * nodal[:, :, c10]
                + (1 - xi) * eta * nodal[:, :, c01] + xi * eta * nodal[:, :, c11])

    def fringe_order(self, stress: np.ndarray) -> np.ndarray:
        """N_f = (s1 - s2) w / f_sigma at the slab's pixels.

        Parameters
        ----------
        stress
            From :meth:`stress` (3, pixels), or :meth:`stresses` (frames, 3, pixels).

        Returns
        -------
        numpy.ndarray
            Fringe order at each pixel (of each frame).

        """
        difference = np.hypot(stress[..., 0, :] - stress[..., 1, :], 2 * stress[..., 2, :])
        return difference * self.slab.width / self.camera.fringe_value

    def render(
        self, stress: np.ndarray, rng: np.random.Generator, *, led: bool = False
    ) -> np.ndarray:
        """One frame (height x width, uint8 or uint16) of the given stress field.

        Parameters
        ----------
        stress
            From :meth:`stress`.
        rng
            The camera noise's random stream.
        led
            Whether the sync LED is lit in this frame.

        Returns
        -------
        numpy.ndarray
            The frame.

        """
        return self.render_frames(stress[None], rng, leds=np.array([led]))[0]

    def render_frames(self, stresses: np.ndarray, rng: np.random.Generator, *,
                      leds: np.ndarray | None = None) -> np.ndarray:
        """Frames (frames x height x width, uint8 or uint16) of stress fields, at once.

        The same frames as :meth:`render` called on each in turn with the same stream
        (the noise is drawn frame after frame), without a loop over them.

        Parameters
        ----------
        stresses
            From :meth:`stresses`.
        rng
            The camera noise's random stream.
        leds
            (frames,) whether the sync LED is lit in each; ``None``: in none.

        Returns
        -------
        numpy.ndarray
            The frames.

        Examples
        --------
        >>> photo = Photoelastic(Slab(elements=16), Camera(width=80, height=40))
        >>> u = np.zeros((2, 2 * 17))
        >>> u[1, :17] = 0.01  # the second frame's contact sheared by 10 um
        >>> one = [photo.render(s, np.random.default_rng(0)) for s in photo.stresses(u)[:1]]
        >>> frames = photo.render_frames(photo.stresses(u), np.random.default_rng(0))
        >>> frames.shape, bool((frames[0] == one[0]).all())
        ((2, 40, 80), True)
        """
        camera = self.camera
        count = stresses.shape[0]
        banded = self.rows != slice(0, camera.height)
        bare = np.full((2, camera.height, camera.width), camera.background)  # LED off, on
        bare[:, self.interface_row :, :] = camera.flat
        bare[(1, *LED_PIXELS)] = 255.0
        if banded:  # a band's film: the rest stays bare
            bare[:, self.rows.stop :, :] = camera.background
        lit = (np.zeros(count, dtype=int) if leds is None else np.asarray(leds, dtype=int))
        # only the rows imaged change from frame to frame: the rest is the bare frame
        frames = self._quantised(bare)[lit]
        imaged = bare[0, self.rows][None].repeat(count, axis=0)
        orders = self.fringe_order(stresses)
        imaged[:, self.inside[self.rows]] = (camera.background
                                             + camera.intensity * np.sin(np.pi * orders) ** 2)
        led = np.zeros(bare.shape[1:], dtype=bool)
        led[LED_PIXELS] = True
        imaged[lit == 1] = np.where(led[self.rows], 255.0, imaged[lit == 1])  # drawn last
        if camera.blur:  # each frame alone: no blur across time
            imaged = ndimage.gaussian_filter(imaged, (0.0, camera.blur, camera.blur))
        if camera.noise:
            imaged += rng.normal(0.0, camera.noise, imaged.shape)
        frames[:, self.rows] = self._quantised(imaged)
        return frames

    def _quantised(self, image: np.ndarray) -> np.ndarray:
        """Grey levels as the camera's bits record them."""
        if self.camera.bits == 16:
            return np.clip(np.round(image * 257.0), 0, 65535).astype(np.uint16)
        return np.clip(np.round(image), 0, 255).astype(np.uint8)
