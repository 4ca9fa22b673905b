"""What the Blender tests' drivers share (run_blender_test.py, run_viewport_test.py): the skip
exit code and reading an image with OpenImageIO."""
import sys

SKIP = 77  # ctest's SKIP_RETURN_CODE


def skip(message):
    print("SKIP: " + message)
    sys.exit(SKIP)


def read_image(path):
    """The pixels of @a path, (height, width, channels) float32, and its channel names."""
    import numpy as np
    import OpenImageIO as oiio
    image = oiio.ImageInput.open(path)
    if image is None:
        sys.exit("FAIL: cannot read %s (%s)" % (path, oiio.geterror()))
    spec = image.spec()
    pixels = np.asarray(image.read_image(format="float")).reshape(spec.height, spec.width, spec.nchannels)
    names = list(spec.channelnames)
    image.close()
    return pixels, names
