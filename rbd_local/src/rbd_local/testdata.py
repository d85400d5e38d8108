"""Real hand photos for tests and benchmarks, fetched from Debian's ``opencv-doc`` package.

The OpenCV documentation (Apache-2.0/BSD) ships two photos of a real hand, ``handSrc.jpg`` and
``handDst.jpg``. They are extracted from the Debian package at test time with
``apt-get download`` and ``dpkg-deb --fsys-tarfile`` (no installation, no root needed for the
download) and cached in a directory of the caller's choice.
"""

import glob
import os
import shutil
import subprocess
import tarfile
import tempfile

PHOTOS = ("handSrc.jpg", "handDst.jpg")
DOC_DIR = "./usr/share/doc/opencv-doc/opencv4/html/"


def fetch_hand_photos(cache_dir: str, timeout: float = 300.0) -> dict[str, str]:
    """Return paths of the two hand photos, downloading them once into ``cache_dir``.

    Args:
        cache_dir: where the JPEGs are kept between runs.
        timeout: seconds allowed for the download.

    Returns:
        Mapping photo name -> path.

    Raises:
        RuntimeError: if apt cannot provide the package or the photos are not in it.
    """
    os.makedirs(cache_dir, exist_ok=True)
    paths = {name: os.path.join(cache_dir, name) for name in PHOTOS}
    if all(os.path.isfile(p) and os.path.getsize(p) > 0 for p in paths.values()):
        return paths
    with tempfile.TemporaryDirectory() as tmp:
        proc = subprocess.run(
            ["apt-get", "download", "opencv-doc"],
            cwd=tmp,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            universal_newlines=True,
            timeout=timeout,
        )
        debs = glob.glob(os.path.join(tmp, "opencv-doc_*.deb"))
        if proc.returncode != 0 or not debs:
            raise RuntimeError("apt-get download opencv-doc failed: %s" % proc.stdout[-500:])
        dpkg = subprocess.Popen(["dpkg-deb", "--fsys-tarfile", debs[0]], stdout=subprocess.PIPE)
        found = set()
        try:
            with tarfile.open(fileobj=dpkg.stdout, mode="r|") as tar:
                for member in tar:
                    name = os.path.basename(member.name)
                    if name in PHOTOS and member.name.startswith(DOC_DIR) and member.isfile():
                        src = tar.extractfile(member)
                        with open(paths[name] + ".part", "wb") as out:
                            shutil.copyfileobj(src, out)
                        os.replace(paths[name] + ".part", paths[name])
                        found.add(name)
                        if len(found) == len(PHOTOS):
                            break
        finally:
            dpkg.stdout.close()
            dpkg.kill()
            dpkg.wait()
    missing = set(PHOTOS) - found
    if missing:
        raise RuntimeError("opencv-doc did not contain %s" % sorted(missing))
    return paths
