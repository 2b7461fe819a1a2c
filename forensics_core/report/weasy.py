"""WeasyPrint, imported without its side effect on Pillow.

Importing WeasyPrint sets ``PIL.ImageFile.LOAD_TRUNCATED_IMAGES = True`` for
the whole process (weasyprint/images.py). The evidence intake must refuse
truncated photos, and refuses to run at all with that flag on, so the flag is
put back as it was. WeasyPrint only ever decodes the report's own complete
images, which do not need it.
"""

from PIL import ImageFile

_before = ImageFile.LOAD_TRUNCATED_IMAGES
import weasyprint  # noqa: E402
from weasyprint.urls import URLFetcher, URLFetcherResponse  # noqa: E402

ImageFile.LOAD_TRUNCATED_IMAGES = _before

__all__ = ["URLFetcher", "URLFetcherResponse", "weasyprint"]
