"""OpenAL Soft through PyOpenAL's low-level ctypes bindings (``openal.al``/``openal.alc``).

PyOpenAL's high-level helpers are not used (``oalQuit`` frees lists while
iterating them; its WAV reader misreads 8-bit files): this module owns every
device, context, source and buffer it creates and frees them in ``close``.

The ``wave:FILE`` flavour is OpenAL Soft's own wave writer: the mixer runs in
real time and writes exactly what a listener would hear to a WAV file (32-bit
float stereo at 44.1 kHz). OpenAL Soft reads its configuration once per
process, on the first device it opens, so the writer's config names a fixed
per-process path which is a symbolic link re-pointed at ``FILE`` before every
device opens: one process can record several files in turn, one at a time. A
process that opened an ``openal`` device first cannot record, and vice versa;
:class:`AudioDeviceError` says so.
"""

from __future__ import annotations

import atexit
import ctypes
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

from services.audio.backend import DISTANCE_MODELS, AudioDeviceError, to_al

_AL_DISTANCE_ENUMS = {
    "none": 0,
    "inverse": 0xD001,
    "inverse_clamped": 0xD002,
    "linear": 0xD003,
    "linear_clamped": 0xD004,
    "exponent": 0xD005,
    "exponent_clamped": 0xD006,
}
_AL_SOURCE_DISTANCE_MODEL = 0x200  # AL_EXT_source_distance_model: alEnable
#: Source properties :meth:`OpenALBackend.configure` sets, in its ``wanted`` order.
_PROPS = ("AL_GAIN", "AL_PITCH", "AL_REFERENCE_DISTANCE", "AL_ROLLOFF_FACTOR",
          "AL_MAX_DISTANCE", "AL_LOOPING", "AL_SOURCE_RELATIVE", "AL_DISTANCE_MODEL")
_ALC_HRTF_SOFT = 0x1992  # ALC_SOFT_HRTF

#: How this process configured OpenAL Soft: None (untouched), "device" or "wave".
_process_mode: str | None = None
_wave_link: Path | None = None
_saved_env: dict[str, str | None] = {}


def _restore_env() -> None:
    """OpenAL Soft has read its configuration: child processes must not inherit it."""
    for key, value in _saved_env.items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value
    _saved_env.clear()


def _load() -> tuple:
    """Import the bindings lazily: a missing libopenal must only disable sound."""
    try:
        from openal import al, alc
    except Exception as exc:  # ExternalLibraryError, OSError
        raise AudioDeviceError(f"OpenAL library unavailable: {exc}") from exc
    return al, alc


def _configure_wave(file: Path) -> None:
    """Point OpenAL Soft's wave writer at ``file`` (config read once per process)."""
    global _process_mode, _wave_link
    if _process_mode == "device":
        raise AudioDeviceError(
            f"wave:{file}: OpenAL Soft already opened a sound device in this process and "
            "reads its configuration only once; record in a fresh process")
    file.parent.mkdir(parents=True, exist_ok=True)
    if _wave_link is None:
        folder = Path(tempfile.mkdtemp(prefix="colosseum-alsoft-"))
        atexit.register(shutil.rmtree, folder, True)  # the link only, never the recording
        _wave_link = folder / "out.wav"
        conf = folder / "alsoft.conf"
        conf.write_text(
            "[general]\ndrivers=wave\nfrequency=44100\nchannels=stereo\nhrtf=false\n"
            f"[wave]\nfile={_wave_link}\n")
        for key, value in (("ALSOFT_CONF", str(conf)), ("ALSOFT_DRIVERS", "wave")):
            _saved_env[key] = os.environ.get(key)
            os.environ[key] = value
    if _wave_link.is_symlink() or _wave_link.exists():
        _wave_link.unlink()
    _wave_link.symlink_to(file.resolve())
    _process_mode = "wave"


class OpenALBackend:
    """An AudioBackend over one OpenAL device and context."""

    def __init__(self, wave_file: str | Path | None = None, hrtf: bool = False) -> None:
        global _process_mode
        al, alc = _load()
        self._al, self._alc = al, alc
        self.wave_file = Path(wave_file) if wave_file is not None else None
        if self.wave_file is not None:
            _configure_wave(self.wave_file)
            self.name = f"wave:{self.wave_file}"
        else:
            if _process_mode == "wave":
                raise AudioDeviceError(
                    "openal: this process configured OpenAL Soft for the wave writer; "
                    "a real device needs a fresh process")
            _process_mode = "device"
            self.name = "openal"
        try:
            device = alc.alcOpenDevice(None)
        except Exception as exc:
            raise AudioDeviceError(f"{self.name}: no audio device ({exc})") from exc
        finally:
            _restore_env()
        if not device:
            raise AudioDeviceError(f"{self.name}: no audio device")
        self._device = device
        attrs = (ctypes.c_int * 3)(_ALC_HRTF_SOFT, 1 if hrtf else 0, 0)
        try:
            self._context = alc.alcCreateContext(device, attrs)
            alc.alcMakeContextCurrent(self._context)
        except Exception as exc:
            alc.alcCloseDevice(device)
            raise AudioDeviceError(f"{self.name}: cannot create a context ({exc})") from exc
        count = ctypes.c_int(0)
        alc.alcGetIntegerv(device, alc.ALC_MONO_SOURCES, 1, ctypes.byref(count))
        self.mono_sources = max(1, count.value)
        self._per_source_model = bool(al.alIsExtensionPresent(b"AL_EXT_source_distance_model"))
        if self._per_source_model:
            al.alEnable(_AL_SOURCE_DISTANCE_MODEL)
        self._sources: set[int] = set()
        self._buffers: set[int] = set()
        #: The last pose sent per source (row ``_slot[source]``), to skip bodies at rest.
        self._slot: dict[int, int] = {}
        self._sent = np.full((64, 6), np.nan, np.float32)
        self._listener: tuple[float, ...] = ()
        self._props: dict[int, list[float | int | None]] = {}
        # pyopenal checks alGetError after every call; the per-frame path checks once.
        self._source3f = al.lib["alSource3f"]
        self._source3f.argtypes = [ctypes.c_uint, ctypes.c_int, ctypes.c_float, ctypes.c_float,
                                   ctypes.c_float]
        self._source3f.restype = None
        self._int = ctypes.c_int(0)
        self._closed = False
        self.set_distance_model("inverse_clamped")

    # -- objects -------------------------------------------------------------
    def gen_sources(self, count: int) -> list[int]:
        ids = (ctypes.c_uint * count)()
        self._al.alGenSources(count, ids)
        self._sources.update(ids)
        return list(ids)

    def delete_sources(self, sources: list[int]) -> None:
        if not sources:
            return
        ids = (ctypes.c_uint * len(sources))(*sources)
        for s in sources:
            self._al.alSourceStop(s)
            self._al.alSourcei(s, self._al.AL_BUFFER, 0)
        self._al.alDeleteSources(len(sources), ids)
        self._sources.difference_update(sources)

    def gen_buffers(self, count: int) -> list[int]:
        ids = (ctypes.c_uint * count)()
        self._al.alGenBuffers(count, ids)
        self._buffers.update(ids)
        return list(ids)

    def delete_buffers(self, buffers: list[int]) -> None:
        if not buffers:
            return
        ids = (ctypes.c_uint * len(buffers))(*buffers)
        self._al.alDeleteBuffers(len(buffers), ids)
        self._buffers.difference_update(buffers)

    def buffer_data(self, buffer: int, pcm: np.ndarray, rate: int) -> None:
        al = self._al
        data = np.ascontiguousarray(pcm, dtype=np.int16)
        fmt = al.AL_FORMAT_STEREO16 if data.ndim == 2 and data.shape[1] == 2 \
            else al.AL_FORMAT_MONO16
        al.alBufferData(buffer, fmt, data.ctypes.data, data.nbytes, int(rate))

    # -- source properties -----------------------------------------------------
    def configure(self, source: int, *, gain: float, pitch: float, ref_distance: float,
                  rolloff: float, max_distance: float, looping: bool, relative: bool,
                  distance_model: str | None) -> None:
        """Set what differs from the source's last use (reused sources repeat most)."""
        al = self._al
        if source in self._slot:
            self._sent[self._slot[source]] = np.nan
        model = _AL_DISTANCE_ENUMS[distance_model or self._model] \
            if self._per_source_model else None
        wanted = [float(gain), float(pitch), float(ref_distance), float(rolloff),
                  float(max_distance), int(looping), int(relative), model]
        last = self._props.get(source)
        self._props[source] = wanted
        for i, (name, value) in enumerate(zip(_PROPS, wanted, strict=True)):
            if last is not None and last[i] == value or value is None:
                continue
            if isinstance(value, float):
                al.alSourcef(source, getattr(al, name), value)
            else:
                al.alSourcei(source, getattr(al, name), value)
        if relative:
            al.alSource3f(source, al.AL_POSITION, 0.0, 0.0, 0.0)
            al.alSource3f(source, al.AL_VELOCITY, 0.0, 0.0, 0.0)

    def set_gain(self, source: int, gain: float) -> None:
        self._al.alSourcef(source, self._al.AL_GAIN, gain)
        if source in self._props:
            self._props[source][0] = float(gain)

    def set_pitch(self, source: int, pitch: float) -> None:
        self._al.alSourcef(source, self._al.AL_PITCH, pitch)
        if source in self._props:
            self._props[source][1] = float(pitch)

    def attach(self, source: int, buffer: int) -> None:
        self._al.alSourceStop(source)
        self._al.alSourcei(source, self._al.AL_BUFFER, buffer)

    def queue(self, source: int, buffers: list[int]) -> None:
        ids = (ctypes.c_uint * len(buffers))(*buffers)
        self._al.alSourceQueueBuffers(source, len(buffers), ids)

    def unqueue_processed(self, source: int) -> list[int]:
        al = self._al
        al.alGetSourcei(source, al.AL_BUFFERS_PROCESSED, ctypes.byref(self._int))
        n = self._int.value
        if n <= 0:
            return []
        ids = (ctypes.c_uint * n)()
        al.alSourceUnqueueBuffers(source, n, ids)
        return list(ids)

    def play(self, source: int) -> None:
        self._al.alSourcePlay(source)

    def stop(self, source: int) -> None:
        self._al.alSourceStop(source)

    def playing(self, source: int) -> bool:
        al = self._al
        al.alGetSourcei(source, al.AL_SOURCE_STATE, ctypes.byref(self._int))
        return self._int.value == al.AL_PLAYING

    # -- space -------------------------------------------------------------
    def set_poses(self, sources: list[int], positions: np.ndarray,
                  velocities: np.ndarray) -> None:
        """The per-frame hot path: unchecked ``alSource3f`` (one ``alGetError`` for
        the batch) and no call at all for a source whose pose is unchanged.

        Updates are not deferred with alcSuspendContext: in OpenAL Soft 1.19
        alcProcessContext spins until the mixer finishes its pass (milliseconds on
        a loaded machine), while sources updated one by one land at most one
        mixing period (~20 ms) apart, which no one hears.
        """
        data = np.empty((len(sources), 6), np.float32)
        data[:, :3] = to_al(positions)
        data[:, 3:] = to_al(velocities)
        slot = self._slot
        try:
            rows = [slot[s] for s in sources]
        except KeyError:
            for s in sources:
                if s not in slot:
                    slot[s] = len(slot)
            if len(slot) > len(self._sent):
                grown = np.full((2 * len(slot), 6), np.nan, np.float32)
                grown[: len(self._sent)] = self._sent
                self._sent = grown
            rows = [slot[s] for s in sources]
        changed = np.flatnonzero((self._sent[rows] != data).any(axis=1))
        if not len(changed):
            return
        self._sent[rows] = data
        ids = [sources[i] for i in changed.tolist()]
        set3f, p_enum, v_enum = self._source3f, self._al.AL_POSITION, self._al.AL_VELOCITY
        for s, (px, py, pz, vx, vy, vz) in zip(ids, data[changed].tolist(), strict=True):
            set3f(s, p_enum, px, py, pz)
            set3f(s, v_enum, vx, vy, vz)
        error = self._al.alGetError()
        if error:
            raise AudioDeviceError(f"{self.name}: moving sources failed (AL error {error:#x})")

    def place(self, source: int, position: np.ndarray, velocity: np.ndarray) -> None:
        p, v = to_al(np.array([position, velocity])).tolist()
        self._source3f(source, self._al.AL_POSITION, *p)
        self._source3f(source, self._al.AL_VELOCITY, *v)
        slot = self._slot.get(source)
        if slot is not None:
            self._sent[slot] = np.nan

    def set_listener(self, position: np.ndarray, velocity: np.ndarray, forward: np.ndarray,
                     up: np.ndarray, gain: float) -> None:
        """Skipped when nothing changed (a still camera costs no AL call)."""
        values = (*to_al(np.array([position, velocity, forward, up])).ravel().tolist(), gain)
        if values == self._listener:
            return
        self._listener = values
        al = self._al
        al.alListener3f(al.AL_POSITION, *values[0:3])
        al.alListener3f(al.AL_VELOCITY, *values[3:6])
        al.alListenerfv(al.AL_ORIENTATION, (ctypes.c_float * 6)(*values[6:12]))
        al.alListenerf(al.AL_GAIN, gain)

    def set_distance_model(self, model: str) -> None:
        if model not in DISTANCE_MODELS:
            raise ValueError(f"unknown distance model {model!r}; "
                             f"choose one of {', '.join(DISTANCE_MODELS)}")
        self._model = model
        self._al.alDistanceModel(_AL_DISTANCE_ENUMS[model])

    def close(self) -> None:
        """Free every source and buffer, then the context and device (idempotent)."""
        if self._closed:
            return
        self._closed = True
        alc = self._alc
        self.delete_sources(sorted(self._sources))
        self.delete_buffers(sorted(self._buffers))
        alc.alcMakeContextCurrent(None)
        alc.alcDestroyContext(self._context)
        alc.alcCloseDevice(self._device)
