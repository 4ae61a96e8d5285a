"""DXF layer names -> what a layer holds (walls, doors, windows, ...), by the naming
conventions drawings come with: AIA / NCS (``A-WALL``, ``S-COLS``, ``A-AREA``), ISO 13567
and BS 1192 with CI/SfB or Uniclass codes (``A-21``, ``A-221--G``, ``EF_25_10``), Swiss and
German FM layers (``E41_AUSSENWAENDE``, ``Z23_NGF-POLYGONE``), Revit and ArchiCAD exports
(``Walls - Exterior``), and the words for wall, door, ... in the common languages.

Names are compared upper-case with umlauts spelled out (Ä -> AE, ß -> SS) and accents
dropped; a word matches a whole token, or a token that is the word with an inflection
(ENDINGS: ``MURS`` in ``MURS_PORTEURS``, ``Walls``, ``TABIQUES``), never a word inside
another (``MUR`` is not in ``murals``); a word listed with ``*`` is a stem that may go on
(``ANNO*``: ``ANNOTATION``); German compounds anywhere (``WAND`` in ``AUSSENWAND``). User
patterns are fnmatch-style, case-insensitive.
"""

from __future__ import annotations

import re
import unicodedata
from fnmatch import fnmatch

ROLES = ("wall", "door", "window", "column", "room", "furniture")

_SPELL = (("Ä", "AE"), ("Ö", "OE"), ("Ü", "UE"), ("ß", "SS"), ("Ø", "OE"), ("Æ", "AE"), ("Å", "AA"), ("Œ", "OE"))


def normalise(name: str) -> str:
    """Upper case, umlauts spelled out, accents dropped: 'Wände' -> 'WAENDE', 'Fenêtre' -> 'FENETRE'."""
    s = str(name).upper()
    for a, b in _SPELL:
        s = s.replace(a, b)
    return "".join(c for c in unicodedata.normalize("NFKD", s) if not unicodedata.combining(c))


# the inflections a listed word may carry and still be that word (plural, gender, case)
ENDINGS = "S ES E EN N I O OS A AS Y X ER ERS ING INGS UNG UNGEN"


def _words(starts: str = "", inside: str = "", exact: str = "") -> re.Pattern:
    """A pattern for words as whole tokens with an inflection (``starts``; a word ending
    in ``*`` a stem that may go on), anywhere (``inside``: compounds, CJK) or as whole
    tokens exactly (``exact``); each a space-separated list."""
    alts = []
    whole = [w for w in starts.split() if not w.endswith("*")]
    stems = [w[:-1] for w in starts.split() if w.endswith("*")]
    if whole:
        alts.append(r"(?<![A-Z])(?:" + "|".join(whole) + ")(?:" + "|".join(ENDINGS.split()) + r")?(?![A-Z])")
    if stems:
        alts.append(r"(?<![A-Z])(?:" + "|".join(stems) + ")")
    if inside.split():
        alts.append("(?:" + "|".join(inside.split()) + ")")
    if exact.split():
        alts.append(r"(?<![A-Z0-9])(?:" + "|".join(exact.split()) + r")(?![A-Z0-9])")
    return re.compile("|".join(alts))


# what a layer holds, by its words (checked in this order: a window before a wall, ...)
_ROLE_WORDS = {
    "door": _words("DOOR TUERE TUEREN PUERTA DEUR DOERR DRZWI DVER KAPI*", "TUER 门 門 扉 ドア 문",
                   "TUR TUREN PORTE PORTES PORTA PORTAS DOER"),
    "window": _words("WINDOW WINDW GLAZ* GLASS GLAS FENSTER FENETRE VERRE VITRAGE VITR VIDRIO VENTANA CRISTAL "
                     "CRYSTAL FINESTR* VETR* JANELA VIDRO RAAM RAMEN VINDU FOENSTER FONSTER OKNA OKNO OKEN PENCERE "
                     "CURTAIN*", "FENSTER VERGLAS 窗 窓 ガラス 창", "WIN WDW WNDW"),
    "column": _words("COLUMN COLS PILLAR POTEAU PILIER PILAR COLUMNA COLONN PILASTR KOLOM* KOLUMN PILAAR SLOUP "
                     "STUETZ STUTZE SAEUL SAULE PFEILER", "STUETZE STUETZEN SAEULE 柱 기둥", "COL"),
    "wall": _words("WALL MUR MURATUR* MURETT* TAMPONAMENT* MACONN* PARED PAREDE PARETE PARETI CLOISON TABIQU "
                   "TRAMEZZ PARTITION PARTN MUUR MUREN VAEG* VEGG SCIAN STENY STENA STENE DUVAR* ALVENARIA MAUER "
                   "SEINAE SEINA СТЕН*",
                   "WAND WAEND MAUER 墙 牆 壁 벽", ""),
    "room": _words("AREA AREE SUPERFIC* ROOM SPACE SPCE RAUM RAEUM NGF NRF BGF HNF NNF NUF FLAECH ZONE ZONA LOCAL "
                   "LOCAUX PIECE ESPACIO RECINTO HABITACI* AMBIENT STANZ RUIMTE POMIESZCZ* MISTNOST",
                   "RAUM RAEUME FLAECHE 房间 房間", "ROM RUM VANI"),
    "furniture": _words("FURN* EQPM EQUIP* MOEBEL MOBEL MOBIL* MUEBLE ARRED* MEUBEL MOEBLER INVENTAR EINRICHT",
                        "MOEBEL 家具", ""),
}
# annotation, sheet and drawing aids: never walls, rooms, ... whatever other word they hold
_ANNOTATION = _words(
    "TEXT TXT TEXTE TEXTO TESTO TEKST SCHRIFT* BESCHRIFT DIMENSION COTE COTA COTATION QUOTA QUOTE BEMASS "
    "MASSLIN* MASSKETT VERMASS ANNO* NOTE SYMB* LABEL IDEN* TITLE* TITEL* PLANKOPF CARTOUCHE CAJETIN RAHMEN "
    "BORDER* SHEET VPORT VIEWPORT DEFPOINTS LEGEND NORTH AXIS AXES ACHS* GRID* RASTER OVHD OVERHEAD "
    "HIDDEN DEMO* ABBRUCH ELEV* SECT* CENTER* CNTR CENTRE* NPLT STEMPEL STAMP ETIQUET*",
    "BESCHRIFTUNG BEMASSUNG STEMPEL",
    "DIM DIMS TAG TAGS NAME NAMES NUM NR AXE ASSE ASSI EJE EJES NORD NORTE PROJ PROJECTION PROJEKTION PROJECTED")
# not walls though they hold parallel lines: stairs, floors, roofs, hatching, services, site
_OTHER = _words(
    "STAIR* TREPP* ESCALIER ESCALER SCALA FLOOR* FLOR BODEN* PISO PAVIM* PLANCHER ROOF DACH* TOIT* TECHO CLNG DECKE "
    "PLAFOND SOFFIT HATCH PATT* SCHRAFF* HACHUR* TRAMA RAYADO SITE TOPO* LANDSCAP* ELEC* PLMB MECH* HVAC LIGHT "
    "LITE SANIT* PLUMB* FIXT* CASEWORK CASE",
    "SCHRAFFUR TREPPE", "")
# ISO 13567 / BS 1192 codes of walls: CI/SfB (21) external, (22) internal walls; Uniclass EF_25 walls
_WALL_CODE = re.compile(r"^(?:[A-Z][-_ ]G?2[12]\d{0,2}(?![0-9])|A2[12]\d?(?![0-9])|(?:EF|SS)[-_ ]25(?![0-9]))")


def layer_role(name: str) -> str | None:
    """'wall', 'door', 'window', 'column', 'room', 'furniture', 'annotation' (text,
    dimensions, title blocks, grids, hidden / overhead / demolition lines), 'other'
    (stairs, floors, hatching, services) or None (the name says nothing), by the
    layer's name alone."""
    n = normalise(name)
    if _ANNOTATION.search(n):
        # a wall layer's hatching ('WAND_SCHRAFFUR') stays a wall layer; its text, dimensions do not
        return "annotation"
    for role in ("door", "window", "column"):
        if _ROLE_WORDS[role].search(n):
            return role
    if _ROLE_WORDS["wall"].search(n) or _WALL_CODE.search(n):
        return "wall"
    for role in ("room", "furniture"):
        if _ROLE_WORDS[role].search(n):
            return role
    return "other" if _OTHER.search(n) or n == "DEFPOINTS" else None


def block_role(block: str) -> str | None:
    """'door', 'window' or 'furniture' when a block's name says so (e.g. 'M_Single-Flush
    Door', 'FENSTER_2FL', 'Desk'), else None."""
    n = normalise(block)
    for role in ("door", "window"):
        if _ROLE_WORDS[role].search(n):
            return role
    return "furniture" if _ROLE_WORDS["furniture"].search(n) or re.search(
        r"(?<![A-Z])(?:DESK|TABLE|CHAIR|SOFA|BED|CABINET|SHELF|TISCH|STUHL|BUREAU|CHAISE|MESA|SILLA)", n) else None


def matches(layer: str, patterns) -> bool:
    """True when ``layer`` matches one of the fnmatch ``patterns`` (case-insensitive)."""
    name = normalise(layer)
    return any(fnmatch(name, normalise(p)) for p in patterns)
