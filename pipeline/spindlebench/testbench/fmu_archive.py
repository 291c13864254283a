"""An FMU's zip checked before anything is unpacked or loaded from it.

Loading an FMU runs its native code (the shared library's constructors run at ``dlopen``,
before any check of ours could): only FMUs from a trusted source should be given to
``--fmu`` or a study's ``fmu =``. What can be checked without running it is checked here,
each problem one line: member names that would unpack outside the folder (absolute, ``..``,
a backslash or a drive colon), encrypted members, compression other than stored/deflate, a
total unpacked size or member count far beyond any machine model's (a zip bomb), a binary
for this platform that is not an ELF shared object, and an instantiation token that is not
the one compiled into that binary (another build's description beside it).
"""

from __future__ import annotations

import zipfile
from pathlib import PurePosixPath

from fmpy import platform_tuple, sharedLibraryExtension

#: Most bytes an FMU may unpack to, and most members: the shipped one is ~5 MB in 6 members.
MAX_UNPACKED_BYTES = 1 << 30
MAX_MEMBERS = 10_000
#: Compression methods zipfile reads without extra libraries and FMI allows (FMI 3.0 §2.5:
#: stored or deflate).
COMPRESSIONS = {zipfile.ZIP_STORED: "stored", zipfile.ZIP_DEFLATED: "deflate"}
_ELF_MAGIC = b"\x7fELF"
_ET_DYN = 3


def unsafe_name(name: str) -> str | None:
    """Why a member name could unpack outside the folder, or None."""
    if "\\" in name:
        return "has a backslash"
    if ":" in name:
        return "has a colon (a drive letter or stream)"
    if name.startswith("/"):
        return "is absolute"
    if ".." in PurePosixPath(name).parts:
        return "climbs out with '..'"
    if "\x00" in name:
        return "has a NUL byte"
    return None


def member_problem(archive: zipfile.ZipFile) -> str | None:
    """What is wrong with the archive's directory, read without unpacking anything."""
    infos = archive.infolist()
    if len(infos) > MAX_MEMBERS:
        return f"{len(infos)} members, more than {MAX_MEMBERS} (a zip bomb?)"
    total = 0
    for info in infos:
        shown = info.filename[:80]
        why = unsafe_name(info.filename)
        if why:
            return f"member name {shown!r} {why}"
        if info.flag_bits & 0x1:
            return f"member {shown} is encrypted"
        if info.compress_type not in COMPRESSIONS:
            return (f"member {shown} uses compression method {info.compress_type} "
                    "(FMUs use stored or deflate)")
        total += info.file_size
    if total > MAX_UNPACKED_BYTES:
        return (f"unpacks to {total:,} bytes, more than {MAX_UNPACKED_BYTES:,} "
                "(a zip bomb?)")
    return None


def binary_problem(archive: zipfile.ZipFile, model_identifier: str) -> str | None:
    """Whether this platform's binary is an ELF shared object (Linux; elsewhere not checked)."""
    if sharedLibraryExtension != ".so":
        return None
    name = f"binaries/{platform_tuple}/{model_identifier}{sharedLibraryExtension}"
    try:
        with archive.open(name) as member:
            head = member.read(18)
    except KeyError:
        return None  # no binary for this platform: the runner says so, with how to build one
    if len(head) < 18 or head[:4] != _ELF_MAGIC:
        return f"member {name} is not an ELF file"
    byteorder = "little" if head[5] == 1 else "big"
    if int.from_bytes(head[16:18], byteorder) != _ET_DYN:
        return f"member {name} is an ELF file but not a shared object"
    return None


def token_problem(archive: zipfile.ZipFile, token: str | None,
                  model_identifier: str) -> str | None:
    """Whether this platform's binary carries the instantiation token of modelDescription.xml
    (``modelica.fmu_export`` compiles it into the library, which checks it when
    instantiated): another build's description beside this binary, or the reverse, is
    refused before the library is loaded."""
    if sharedLibraryExtension != ".so" or not token:
        return None
    name = f"binaries/{platform_tuple}/{model_identifier}{sharedLibraryExtension}"
    try:
        binary = archive.read(name)
    except KeyError:
        return None  # no binary for this platform: the runner says so
    if token.encode("utf-8") not in binary:
        return (f"modelDescription.xml's instantiationToken {token[:40]!r} is not the one "
                f"compiled into {name} (a description of another build?)")
    return None
