;;;; tangled/workshop.lisp -- GENERATED from physics.org by 'make tangle'. Do not edit.

;; [[file:../physics.org::#W0RKSH][The engine and its workshop:2]]
(in-package #:luv-physics)

(export '(;; The image knows its anchors (#BSOZ3U), reading and reloading the page (#0QBGZO, #OWNJGP)
          anchor-definitions definition-anchor section reload-section reload-changed
          ;; Scenes are definitions (#K5DF9S)
          define-physics-scene physics-scene physics-scene-name physics-scene-features
          physics-scene-seconds physics-scene-moments physics-scene-text find-physics-scene
          make-scene-world unknown-physics-scene invalid-physics-scene-clause
          ;; Random operation sequences (#M9W5P7)
          run-fuzz-campaign run-physics-soak
          ;; The basin, the main job, what a step and a query cost (#B4S1NS, #D3M0SC, #B3NCH5, #QB3NCH)
          make-basin-terrain make-basin-world run-default-scene run-basin-benchmark run-query-benchmark
          ;; The recorder, the standard scenes, the viewer and the pictures (#G4WXCJ, #3X6XN8,
          ;; #RH7T05, #UFK5EA), the index of the interface (#LW3YHU)
          physics-recording start-physics-recording stop-physics-recording
          physics-recording-frame-count *physics-scenes* run-physics-scene
          write-physics-viewer write-world-viewer write-scene-picture write-api-index))
;; The engine and its workshop:2 ends here

;; [[file:../physics.org::#HAPODD][The image knows its anchors:1]]
(defvar *definitions* '()
  "Every registered definition record, file by file, each file's in order. #HAPODD")

(defvar *registered-files* '()
  "Truenames of the tangled source files whose definitions are registered. #HAPODD")

(defvar *page-pathname* nil
  "Truename of the Org page the registered files were tangled from. #HAPODD")
;; The image knows its anchors:1 ends here

;; [[file:../physics.org::#2HB3Y9][Read the definitions of a tangled file:1]]
(defun starts-with (prefix string)
  "True if STRING begins with PREFIX. #2HB3Y9"
  (and (<= (length prefix) (length string))
       (string= prefix string :end2 (length prefix))))

(defun read-file-text (pathname)
  "The contents of the UTF-8 text file PATHNAME as one string. #2HB3Y9"
  (with-open-file (in pathname :external-format :utf-8)
    (let* ((text (make-string (file-length in)))
           (end (read-sequence text in)))
      (subseq text 0 end))))

(defun split-lines (text)
  "The lines of TEXT as a vector of strings without their newlines. #2HB3Y9"
  (let ((lines (make-array 0 :adjustable t :fill-pointer t))
        (start 0))
    (loop for end = (position #\Newline text :start start)
          do (vector-push-extend (subseq text start (or end (length text))) lines)
             (if end (setf start (1+ end)) (return)))
    lines))

(defun link-comment-anchor (line)
  "The anchor named by LINE if it is a link comment (';; ' and an Org file link
ending in ::#ANCHOR), else NIL.  The second value is the linked file's name. #2HB3Y9"
  (let ((prefix (concatenate 'string ";; " "[[" "file:")))
    (when (starts-with prefix line)
      (let* ((page-end (search "::#" line :start2 (length prefix)))
             (anchor-end (and page-end (position #\] line :start page-end))))
        (when anchor-end
          (values (subseq line (+ page-end 3) anchor-end)
                  (subseq line (length prefix) page-end)))))))

(defun line-anchors (lines)
  "For each of LINES, the anchor of the nearest link comment at or above it, or NIL. #2HB3Y9"
  (let ((anchor nil))
    (map 'vector (lambda (line) (setf anchor (or (link-comment-anchor line) anchor)))
         lines)))

(defun block-comment-end (text start)
  "The position just after the #| ... |# comment whose body starts at START in TEXT. #2HB3Y9"
  (let ((depth 1) (i start) (n (length text)))
    (loop while (and (plusp depth) (< (1+ i) n))
          do (cond ((and (char= #\| (char text i)) (char= #\# (char text (1+ i))))
                    (decf depth) (incf i 2))
                   ((and (char= #\# (char text i)) (char= #\| (char text (1+ i))))
                    (incf depth) (incf i 2))
                   (t (incf i))))
    (if (plusp depth) n i)))

(defun skip-blanks-and-comments (text start)
  "The first position at or after START in TEXT that is neither blank nor inside a comment. #2HB3Y9"
  (let ((i start) (n (length text)))
    (loop
      (cond ((>= i n) (return n))
            ((member (char text i) '(#\Space #\Tab #\Newline #\Return #\Page)) (incf i))
            ((char= #\; (char text i)) (setf i (or (position #\Newline text :start i) n)))
            ((and (char= #\# (char text i)) (< (1+ i) n) (char= #\| (char text (1+ i))))
             (setf i (block-comment-end text (+ i 2))))
            (t (return i))))))

(defun defining-operator-p (operator)
  "True if OPERATOR is a symbol whose name starts with DEF, as DEFUN and DEFINE-... do. #2HB3Y9"
  (and (symbolp operator)
       (< 3 (length (symbol-name operator)))
       (starts-with "DEF" (symbol-name operator))))

(defun toplevel-definitions (form)
  "The definitions FORM makes at toplevel: FORM itself, or those inside PROGN, EVAL-WHEN and LOCALLY. #2HB3Y9"
  (cond ((atom form) '())
        ((member (car form) '(progn locally)) (mapcan #'toplevel-definitions (cdr form)))
        ((eq (car form) 'eval-when) (mapcan #'toplevel-definitions (cddr form)))
        ((defining-operator-p (car form)) (list form))
        (t '())))

(defun definition-name (kind form)
  "The name FORM, a definition of KIND, defines. #2HB3Y9"
  (let ((name (second form)))
    (cond ((and (eq kind :defstruct) (consp name)) (first name))
          ((and (eq kind :defpackage) (symbolp name)) (symbol-name name))
          (t name))))

(defun body-docstring (body)
  "The docstring at the head of a function BODY: a string among its declarations, followed by more forms. #2HB3Y9"
  (loop for (form . more) on body
        do (cond ((and (stringp form) more) (return form))
                 ((and (consp form) (eq (car form) 'declare)))
                 (t (return nil)))))

(defun option-docstring (options)
  "The string of a (:DOCUMENTATION string) among OPTIONS, or NIL. #2HB3Y9"
  (loop for option in options
        when (and (consp option) (eq (car option) :documentation) (stringp (second option)))
          return (second option)))

(defun definition-docstring (kind form)
  "The docstring FORM, a definition of KIND, gives itself, or NIL. #2HB3Y9"
  (flet ((string-or-nil (x) (and (stringp x) x)))
    (case kind
      ((:defun :defmacro :deftype :define-compiler-macro :define-setf-expander)
       (body-docstring (cdddr form)))
      (:defmethod (body-docstring (rest (member-if #'listp (cddr form)))))
      ((:defvar :defparameter :defconstant) (string-or-nil (fourth form)))
      (:defgeneric (option-docstring (cdddr form)))
      ((:defclass :define-condition) (option-docstring (nthcdr 4 form)))
      (:defpackage (option-docstring (cddr form)))
      (:defstruct (string-or-nil (third form)))
      (:define-modify-macro (string-or-nil (fifth form)))
      (:define-symbol-macro nil)
      (t (or (option-docstring (cddr form))
             (loop for (key value) on (cddr form)
                   when (and (eq key :documentation) (stringp value)) return value)
             (find-if #'stringp (cddr form)))))))

(defun scan-tangled-text (text)
  "One plist (:NAME :KIND :ANCHOR :LINE :SOURCE-LINE :DOCSTRING) per definition in TEXT,
a tangled file's contents, in order.  :SOURCE-LINE is the text of the form's first line. #2HB3Y9"
  (let* ((lines (split-lines text))
         (anchors (line-anchors lines))
         (*package* (find-package '#:cl-user))
         (*read-eval* t)
         (records '())
         (position 0)
         (line 1))
    (loop
      (let ((start (skip-blanks-and-comments text position)))
        (when (>= start (length text))
          (return (nreverse records)))
        (incf line (count #\Newline text :start position :end start))
        (multiple-value-bind (form end) (read-from-string text t nil :start start)
          (when (and (consp form) (eq (car form) 'in-package))
            (setf *package* (find-package (second form))))
          (dolist (definition (toplevel-definitions form))
            (let ((kind (intern (symbol-name (car definition)) :keyword)))
              (push (list :name (definition-name kind definition)
                          :kind kind
                          :anchor (aref anchors (1- line))
                          :line line
                          :source-line (aref lines (1- line))
                          :docstring (definition-docstring kind definition))
                    records)))
          (incf line (count #\Newline text :start start :end end))
          (setf position end))))))
;; Read the definitions of a tangled file:1 ends here

;; [[file:../physics.org::#UIQ8J5][Find a definition's line on the page:1]]
(defun heading-line-p (line)
  "True if LINE is an Org heading: one or more stars, then a space. #UIQ8J5"
  (let ((stars (or (position #\* line :test-not #'char=) (length line))))
    (and (plusp stars)
         (< stars (length line))
         (char= #\Space (char line stars)))))

(defun page-sections (lines)
  "A hash table from each anchor of the page LINES to (FIRST . LAST), the 1-based lines of its section. #UIQ8J5"
  (let ((sections (make-hash-table :test 'equal))
        (headings (loop for i from 1 to (length lines)
                        when (heading-line-p (aref lines (1- i))) collect i)))
    (loop for (first next) on headings
          for last = (if next (1- next) (length lines))
          when (and (< first last)
                    (string-equal ":PROPERTIES:" (string-trim '(#\Space #\Tab) (aref lines first))))
            do (loop for i from (+ first 2) to last
                     for text = (string-trim '(#\Space #\Tab) (aref lines (1- i)))
                     until (string-equal ":END:" text)
                     when (starts-with ":CUSTOM_ID:" text)
                       do (setf (gethash (string-trim '(#\Space #\Tab) (subseq text 11)) sections)
                                (cons first last))))
    sections))

(defun unescape-org-line (line)
  "LINE of an Org source block as tangling writes it: the protective comma before *, #+ or ,* removed. #UIQ8J5"
  (let* ((indent (or (position-if-not (lambda (c) (member c '(#\Space #\Tab))) line)
                     (length line)))
         (rest (subseq line indent))
         (after-commas (string-left-trim "," rest)))
    (if (and (starts-with "," rest)
             (or (starts-with "*" after-commas) (starts-with "#+" after-commas)))
        (concatenate 'string (subseq line 0 indent) (subseq rest 1))
        line)))

(defun page-line (lines section text &optional (from (car section)))
  "The first line number, from FROM to the end of SECTION, whose line of the page LINES tangles to TEXT. #UIQ8J5"
  (loop for i from from to (cdr section)
        when (string= text (unescape-org-line (aref lines (1- i))))
          return i))
;; Find a definition's line on the page:1 ends here

;; [[file:../physics.org::#BSOZ3U][Register a file and answer by anchor or by name:1]]
(defun register-tangled-file (pathname)
  "Register the definitions of PATHNAME, a file tangled from the page, in place of its earlier ones; return their number. #BSOZ3U"
  (let ((source (and pathname (probe-file pathname))))
    (unless source
      (warn "luv-physics: cannot register the definitions of ~S: no such file." pathname)
      (return-from register-tangled-file 0))
    (let* ((text (read-file-text source))
           (page-name (loop for line across (split-lines text)
                            thereis (nth-value 1 (link-comment-anchor line))))
           (page (and page-name (probe-file (merge-pathnames page-name source))))
           (page-lines (if page (split-lines (read-file-text page)) (vector)))
           (sections (page-sections page-lines))
           (file (if page
                     (enough-namestring source (make-pathname :name nil :type nil :version nil
                                                              :defaults page))
                     (file-namestring source)))
           (cursors (make-hash-table :test 'equal))
           ;; the tangled and page lines of the last record: the definitions of one form share them
           (previous nil)
           (records
             (loop for scanned in (scan-tangled-text text)
                   collect (destructuring-bind (&key name kind anchor line source-line docstring)
                               scanned
                             (let* ((section (and anchor (gethash anchor sections)))
                                    (org-line
                                      (if (eql line (car previous))
                                          (cdr previous)
                                          (and section
                                               (or (page-line page-lines section source-line
                                                              (gethash anchor cursors (car section)))
                                                   (page-line page-lines section source-line))))))
                               (when org-line
                                 (setf (gethash anchor cursors) (1+ org-line)))
                               (setf previous (cons line org-line))
                               (list :name name :kind kind :anchor anchor :file file
                                     :line line :org-line org-line :docstring docstring))))))
      (setf *definitions* (append (remove file *definitions*
                                          :key (lambda (record) (getf record :file))
                                          :test #'equal)
                                  records)
            *registered-files* (append (remove source *registered-files* :test #'equal)
                                       (list source))
            *page-pathname* (or page *page-pathname*))
      (note-loaded-file file text records)
      (length records))))

(defun anchor-definitions (anchor)
  "The definition records tangled from section ANCHOR (string or symbol, leading # ignored), in file order. #BSOZ3U"
  (let ((id (string-left-trim "#" (string anchor))))
    (remove-if-not (lambda (record) (equal id (getf record :anchor))) *definitions*)))

(defun definition-anchor (name &optional kind)
  "The anchor of the section defining NAME (as a definition of KIND, if given), and its line on the page. #BSOZ3U"
  (let ((record (find-if (lambda (record)
                           (and (equal name (getf record :name))
                                (or (null kind) (eq kind (getf record :kind)))))
                         *definitions*)))
    (if record
        (values (getf record :anchor) (getf record :org-line))
        (values nil nil))))
;; Register a file and answer by anchor or by name:1 ends here

;; [[file:../physics.org::#0QBGZO][Read a section's code from the page:1]]
(defun header-tangle (text)
  "The value of the :tangle header argument in TEXT, or NIL. #0QBGZO"
  (let ((at (search ":tangle " text)))
    (when at
      (let ((start (position #\Space text :start (+ at 8) :test-not #'char=)))
        (when start
          (subseq text start (or (position #\Space text :start start) (length text))))))))

(defun page-code-blocks (lines)
  "Each Lisp block of the page LINES as (ANCHOR FILE BEGIN FIRST LAST): its section's anchor, the
file it tangles to (\"no\" for none), and the lines of its #+begin_src, first and last code line. #0QBGZO"
  (let ((headings '()) (default "no") (anchor nil) (drawer nil) (open nil) (blocks '()))
    ;; HEADINGS: (level . tangle) of the enclosing headings, innermost first
    (loop for i from 1 to (length lines)
          for line = (aref lines (1- i))
          for text = (string-trim '(#\Space #\Tab) line)
          do (cond (open
                    (when (string-equal "#+end_src" text)
                      (push (append open (list (1- i))) blocks)
                      (setf open nil)))
                   ((heading-line-p line)
                    (let ((level (position #\* line :test-not #'char=)))
                      (loop while (and headings (>= (car (first headings)) level)) do (pop headings))
                      (push (cons level nil) headings)
                      (setf anchor nil drawer t)))
                   ((and drawer (starts-with ":" text))
                    (cond ((starts-with ":CUSTOM_ID:" text)
                           (setf anchor (string-trim '(#\Space #\Tab) (subseq text 11))))
                          ((starts-with ":header-args:lisp" text)
                           (setf (cdr (first headings)) (or (header-tangle text) (cdr (first headings)))))))
                   ((and (null headings) (starts-with "#+PROPERTY: header-args:lisp " text))
                    (setf default (or (header-tangle text) default)))
                   ((and (<= 16 (length text)) (string-equal "#+begin_src lisp" text :end2 16)
                         (or (= 16 (length text)) (char= #\Space (char text 16))))
                    (setf drawer nil
                          open (list anchor
                                     (or (header-tangle text)
                                         (loop for (nil . file) in headings thereis file)
                                         default)
                                     i (1+ i))))
                   (t (setf drawer nil))))
    (nreverse blocks)))

(defun block-forms (lines anchor file begin first last)
  "The toplevel forms of page LINES FIRST..LAST, a block of section ANCHOR tangling to FILE whose
header is line BEGIN, as property lists (:anchor :file :block :line :end :text :form). #0QBGZO"
  (let* ((code (map 'vector #'unescape-org-line (subseq lines (1- first) last)))
         (text (format nil "~{~A~^~%~}" (coerce code 'list)))
         (*read-eval* t)
         (forms '())
         (position 0))
    (loop
      (let ((start (skip-blanks-and-comments text position)))
        (when (>= start (length text))
          (return (nreverse forms)))
        (multiple-value-bind (form end) (read-from-string text t nil :start start)
          (let ((from (count #\Newline text :end start))
                (to (count #\Newline text :end (max start (1- end)))))
            (when (and (consp form) (eq (car form) 'in-package))
              (setf *package* (find-package (second form))))
            (push (list :anchor anchor :file file :block begin
                        :line (+ first from) :end (+ first to)
                        :text (format nil "~{~A~^~%~}" (coerce (subseq code from (1+ to)) 'list))
                        :form form)
                  forms))
          (setf position end))))))

(defun page-forms (lines files)
  "The forms of every block of the page LINES that tangles to one of FILES, in the order FILES
are loaded and, within a file, in page order. #0QBGZO"
  (let ((*package* (find-package '#:luv-physics)))
    (loop for file in files
          append (loop for (anchor target begin first last) in (page-code-blocks lines)
                       when (equal target file)
                         append (block-forms lines anchor file begin first last)))))

(defun engine-files ()
  "The tangled files of the loaded system, relative to the page, in load order. #0QBGZO"
  (remove-duplicates (mapcar (lambda (record) (getf record :file)) *definitions*)
                     :test #'equal :from-end t))

(defun form-definitions (form)
  "Each (NAME KIND) that FORM, a toplevel form, defines. #0QBGZO"
  (loop for definition in (toplevel-definitions form)
        for kind = (intern (symbol-name (car definition)) :keyword)
        collect (list (definition-name kind definition) kind)))

(defun page-lines-of (page)
  "The lines of PAGE (by default the page the loaded files were tangled from), or an error. #0QBGZO"
  (let ((page (or page *page-pathname*)))
    (unless (and page (probe-file page))
      (error "luv-physics: no page to read: ~S (load the system from its repository)" page))
    (split-lines (read-file-text page))))

(defun find-section (lines anchor)
  "The (FIRST . LAST) lines of section ANCHOR (string or symbol, leading # ignored) in LINES, or an
error naming the anchor. #0QBGZO"
  (let ((id (string-left-trim "#" (string anchor))))
    (or (gethash id (page-sections lines))
        (error "luv-physics: the page has no section ~S" id))))

(defun section (anchor &key page (stream *standard-output*))
  "Print the title and lines of section ANCHOR of PAGE, its definitions with their lines on the
page and in the tangled file, and its claims with their lines; return the title. #0QBGZO"
  (let* ((lines (page-lines-of page))
         (id (string-left-trim "#" (string anchor)))
         (range (find-section lines id))
         (heading (aref lines (1- (car range))))
         (title (string-trim " *" (subseq heading 0 (or (search "   " heading) (length heading)))))
         (prefix (format nil "#+name: ~A-" id))
         (*package* (find-package '#:luv-physics)))
    (format stream "~&~A  ~A~%  ~A:~D-~D~%" id title
            (file-namestring (or page *page-pathname*)) (car range) (cdr range))
    (let ((records (anchor-definitions id)))
      (format stream "  ~D definition~:P~:[~;:~]~%" (length records) records)
      (dolist (r records)
        (format stream "    ~5D  ~(~14A~) ~(~S~)  ~A:~D~%" (getf r :org-line) (getf r :kind)
                (getf r :name) (getf r :file) (getf r :line))))
    (let ((claims (loop for i from (car range) to (cdr range)
                        for text = (aref lines (1- i))
                        when (starts-with prefix text)
                          collect (cons (1+ i) (subseq text (length prefix))))))
      (format stream "  ~D claim~:P~:[~;:~]~%" (length claims) claims)
      (loop for (line . slug) in claims
            do (format stream "    ~5D  ~A~%" line slug)))
    (let* ((forms (page-forms lines (engine-files)))
           (own (remove id forms :key (lambda (form) (getf form :anchor)) :test-not #'equal))
           (copied (remove-duplicates (loop for form in own
                                            append (remove-if-not #'symbolp (form-expanders (getf form :form))))))
           (users (remove id (remove-duplicates (mapcar (lambda (form) (getf form :anchor)) (reload-closure own forms))
                                                :test #'equal :from-end t)
                          :test #'equal)))
      (format stream "  ~:[Nothing it defines is copied into its users.~;Copied into its users: ~:*~{~(~A~)~^ ~}~]~%"
              copied)
      (when users
        (format stream "  Reloading it also recompiles forms of ~{~A~^ ~}.~%" users)))
    title))
;; Read a section's code from the page:1 ends here

;; [[file:../physics.org::#OWNJGP][Reload a section into the running image:1]]
(defvar *loaded-file-texts* (make-hash-table :test 'equal)
  "The text of each registered tangled file (relative to the page) as it was loaded. #OWNJGP")

(defvar *loaded-forms* nil
  "A hash table from each loaded form's key to the text loaded under it, or NIL until a reload
builds it from *loaded-file-texts*. #OWNJGP")

(defvar *parameter-defaults* (make-hash-table :test 'eq)
  "For each defparameter of the page, the value its last evaluation gave. #OWNJGP")

(defun note-loaded-file (file text records)
  "Keep TEXT, the loaded tangled FILE, and the value of each defparameter among its RECORDS. #OWNJGP"
  (setf (gethash file *loaded-file-texts*) text
        *loaded-forms* nil)
  (dolist (record records)
    (let ((name (getf record :name)))
      (when (and (eq :defparameter (getf record :kind)) (symbolp name) (boundp name))
        (setf (gethash name *parameter-defaults*) (symbol-value name))))))

(defun form-keys (forms)
  "The key of each of FORMS: (FILE ANCHOR NAMES N), N counting the earlier FORMS with the same
file, anchor and names. #OWNJGP"
  (let ((seen (make-hash-table :test 'equal)))
    (mapcar (lambda (form)
              (let ((base (list (getf form :file) (getf form :anchor)
                                (form-definitions (getf form :form)))))
                (append base (list (1- (incf (gethash base seen 0)))))))
            forms)))

(defun tangled-text-forms (file text)
  "The toplevel forms of TEXT, the tangled FILE, as page-forms gives them (:block and :line being
lines of the tangled file). #OWNJGP"
  (let* ((lines (split-lines text))
         (anchors (line-anchors lines))
         (*package* (find-package '#:luv-physics)))
    ;; chunks of one anchor, split where the link comment changes or repeats
    (loop with start = 0
          for i from 0 to (length lines)
          when (or (= i (length lines)) (link-comment-anchor (aref lines i)))
            append (prog1 (when (and (< start i) (aref anchors start))
                            (block-forms lines (aref anchors start) file (1+ start) (1+ start) i))
                     (setf start (1+ i))))))

(defun loaded-forms ()
  "The table of *loaded-forms*, built from the registered files' texts when it is NIL. #OWNJGP"
  (or *loaded-forms*
      (let ((table (make-hash-table :test 'equal)))
        (loop for file in (engine-files)
              for text = (gethash file *loaded-file-texts*)
              when text
                do (let ((forms (tangled-text-forms file text)))
                     (loop for form in forms for key in (form-keys forms)
                           do (setf (gethash key table) (getf form :text)))))
        (setf *loaded-forms* table))))

(defun form-expanders (form &optional compile-time)
  "The names FORM defines that its users copy when they are compiled: macros, setf expanders,
types, symbol macros, inline functions, and (COMPILE-TIME) whatever is defined at compile time;
the page's own defining macros are expanded to see what they define. #OWNJGP"
  (cond ((atom form) '())
        ((member (car form) '(progn locally))
         (loop for f in (cdr form) append (form-expanders f compile-time)))
        ((eq (car form) 'eval-when)
         (loop with now = (or compile-time (and (member :compile-toplevel (second form)) t))
               for f in (cddr form) append (form-expanders f now)))
        ((eq (car form) 'declaim)
         (loop for spec in (cdr form)
               when (and (consp spec) (eq (car spec) 'inline)) append (copy-list (cdr spec))))
        ((member (car form) '(defmacro define-compiler-macro defsetf deftype define-symbol-macro
                              define-modify-macro define-setf-expander))
         (list (second form)))
        ((and (eq (car form) 'defun)
              (or compile-time (eq 'inline (sb-int:info :function :inlinep (second form)))))
         (list (second form)))
        ((and compile-time (defining-operator-p (car form)) (symbolp (second form)))
         (list (second form)))
        ((and (symbolp (car form)) (eq (symbol-package (car form)) (find-package '#:luv-physics))
              (macro-function (car form)))
         (form-expanders (macroexpand-1 form) compile-time))
        (t '())))

(defun form-tokens (form)
  "The upcased words of FORM's text, as a hash table: the names it may mention. #OWNJGP"
  (let ((tokens (make-hash-table :test 'equal))
        (text (getf form :text)))
    (loop with start = 0
          for i from 0 to (length text)
          when (or (= i (length text)) (member (char text i) '(#\Space #\Tab #\Newline #\( #\) #\' #\` #\, #\" #\# #\; #\|)))
            do (when (< start i) (setf (gethash (string-upcase (subseq text start i)) tokens) t))
               (setf start (1+ i)))
    tokens))

(defun reload-closure (selected forms &optional (seeds selected))
  "SELECTED, some of FORMS, with every form of FORMS that mentions a name that SEEDS (by default
SELECTED) copy into their users (see form-expanders), then the users of what those users copy, and
so on, in the order of FORMS. #OWNJGP"
  (let ((chosen (make-hash-table :test 'eq))
        (tokens (make-hash-table :test 'eq))
        (queue (copy-list seeds)))
    (dolist (form selected) (setf (gethash form chosen) t))
    (loop while queue
          do (let ((names (remove-if-not #'symbolp (form-expanders (getf (pop queue) :form)))))
               (when names
                 (dolist (user forms)
                   (unless (gethash user chosen)
                     (let ((words (or (gethash user tokens) (setf (gethash user tokens) (form-tokens user)))))
                       (when (some (lambda (name) (gethash (symbol-name name) words)) names)
                         (setf (gethash user chosen) t)
                         (push user queue))))))))
    (remove-if-not (lambda (form) (gethash form chosen)) forms)))

(defun line-position (lines line)
  "The character position, counted from 1 as Emacs counts, where LINE of LINES starts. #OWNJGP"
  (1+ (loop for i from 0 below (1- line) sum (1+ (length (aref lines i))))))

(defun compiler-error-message (diagnostics)
  "The first message the compiler printed after \"caught ERROR\" in DIAGNOSTICS, its output, on
one line; NIL if it caught none. #OWNJGP"
  (let ((at (search "caught ERROR" diagnostics)))
    (when at
      (let* ((start (or (position #\Newline diagnostics :start at) (length diagnostics)))
             (end (or (search (format nil "~%; ~%") diagnostics :start2 start)
                      (search (format nil "~%~%") diagnostics :start2 start)
                      (length diagnostics))))
        (format nil "~{~A~^ ~}"
                (loop for line across (split-lines (subseq diagnostics start end))
                      for text = (string-trim " ;" line)
                      unless (string= text "") collect text))))))

(defun load-page-text (text page position)
  "Compile TEXT, the page PAGE's text from character POSITION, in the engine's package with the
page as its source, and load it; return the warnings, which are not printed. Signal an error,
without loading, when the compiler caught an error in TEXT. #OWNJGP"
  (let* ((name (namestring page))
         (source (merge-pathnames (format nil "luv-physics-reload-~36R.lisp" (random (expt 36 8) (make-random-state t)))
                                  (or (sb-ext:posix-getenv "TMPDIR") "/tmp/")))
         (fasl (compile-file-pathname source))
         (diagnostics (make-string-output-stream))
         (warnings '()))
    (unwind-protect
         (progn
           (with-open-file (out source :direction :output :if-exists :supersede :external-format :utf-8)
             (write-string text out))
           (handler-bind ((sb-ext:compiler-note #'muffle-warning)
                          ;; a reload redefines on purpose
                          (sb-kernel:redefinition-warning #'muffle-warning)
                          (warning (lambda (w) (push w warnings) (muffle-warning w))))
             (let ((*package* (find-package '#:luv-physics)) (*read-eval* t)
                   (*compile-verbose* nil) (*compile-print* nil) (*load-verbose* nil)
                   (*error-output* diagnostics))
               (with-compilation-unit (:source-plist (list :emacs-buffer name :emacs-filename name
                                                           :emacs-package "LUV-PHYSICS"
                                                           :emacs-position position :emacs-string text)
                                       :source-namestring name :allow-other-keys t)
                 (let* ((output (compile-file source :output-file fasl :external-format :utf-8))
                        (caught (compiler-error-message (get-output-stream-string diagnostics))))
                   (cond ((null output) (error "the text did not compile~@[: ~A~]" caught))
                         ;; a form compiled with errors would load as a form that signals them
                         (caught (error "compile error: ~A" caught))
                         (t (load output))))))))
      (when (probe-file source) (delete-file source))
      (when (probe-file fasl) (delete-file fasl)))
    (nreverse warnings)))

(defvar *stale-forms* (make-hash-table :test 'equal)
  "The keys of the forms a failed reload had to load and did not: the form that failed and the
users after it, which still hold what they copied before. The next reload loads them. #OWNJGP")

(defun reload-forms (selected forms lines page label &optional (started (get-internal-real-time)))
  "Load SELECTED, forms of the page PAGE (whose LINES and FORMS are given), with every user they
need recompiled and every form a failed reload left stale, keeping the parameters the user
changed; return and print one line of summary starting with LABEL and ending with the seconds
since STARTED. When a form fails, the summary names its page line, and the forms not loaded are
left stale for the next reload. #OWNJGP"
  (let* ((selected (remove-if (lambda (form)
                                (let ((read (getf form :form)))
                                  (and (consp read) (eq 'register-tangled-file (car read)))))
                              selected))
         (key-of (let ((table (make-hash-table :test 'eq)))
                   (loop for form in forms for key in (form-keys forms) do (setf (gethash form table) key))
                   table))
         ;; only a form whose text changed can change what its users copy
         (changed (let ((table (loaded-forms)))
                    (remove-if (lambda (form) (equal (getf form :text) (gethash (gethash form key-of) table)))
                               selected)))
         (stale (remove-if-not (lambda (form) (gethash (gethash form key-of) *stale-forms*)) forms))
         (chosen (let ((closure (reload-closure selected forms changed)))
                   (remove-if-not (lambda (form) (or (member form closure :test #'eq) (member form stale :test #'eq)))
                                  forms)))
         (users (set-difference chosen selected))
         (kept '()) (warnings '()) (failure nil) (failed nil) (left 0))
    (flet ((load-run (run)
             ;; load RUN, forms next to each other in one block; on an error the tuned
             ;; parameters still get their values back
             (let* ((parameters (loop for form in run
                                      append (loop for (name kind) in (form-definitions (getf form :form))
                                                   when (and (eq kind :defparameter) (boundp name))
                                                     collect name)))
                    (tuned (remove-if (lambda (name)
                                        (multiple-value-bind (default known) (gethash name *parameter-defaults*)
                                          (or (not known) (equal default (symbol-value name)))))
                                      parameters))
                    (saved (mapcar #'symbol-value tuned))
                    (first (getf (first run) :line)))
               (unwind-protect
                    (progn
                      (setf warnings (append warnings
                                             (load-page-text (format nil "~{~A~^~%~}" (mapcar (lambda (f) (getf f :text)) run))
                                                             page (line-position lines first))))
                      (dolist (name parameters)
                        (setf (gethash name *parameter-defaults*) (symbol-value name))))
                 (loop for name in tuned for value in saved
                       do (setf (symbol-value name) value) (pushnew name kept)))
               (let ((table (loaded-forms)))
                 (dolist (form run)
                   (setf (gethash (gethash form key-of) table) (getf form :text))
                   (remhash (gethash form key-of) *stale-forms*))))))
      (loop while chosen
            do (let ((run (list (pop chosen))))
                 (loop while (and chosen
                                  (eql (getf (first chosen) :block) (getf (first run) :block))
                                  (eq (first chosen) (second (member (first run) forms))))
                       do (push (pop chosen) run))
                 (setf run (nreverse run))
                 (handler-case (load-run run)
                   (error (e)
                     ;; which form failed: the run's forms one at a time, up to the one that fails
                     (setf failure e failed (first run))
                     (when (rest run)
                       (dolist (form run)
                         (handler-case (load-run (list form))
                           (error (again) (setf failure again failed form) (return)))))
                     ;; what is not loaded stays stale until a reload loads it
                     (let ((unloaded (append (member failed run) chosen)))
                       (dolist (form unloaded)
                         (setf (gethash (gethash form key-of) *stale-forms*) t))
                       (setf left (length unloaded) chosen '()
                             users (remove-if (lambda (form) (member form unloaded :test #'eq)) users))))))))
    (refresh-page-lines forms)
    (let ((summary
            (format nil "~A: ~D form~:P~@[ (~A)~]~:[~*~;, ~:*~D user~:P recompiled (~{~A~^ ~})~]~
                         ~@[, ~D stale from a failed reload~]~
                         ~@[, kept ~{~(~A~)~^ ~}~], ~D warning~:P~@[ (first: ~A)~], ~,2F s~
                         ~@[; FAILED at ~A~]~@[: ~A~]~@[; ~D form~:P left stale, which the next reload loads~]"
                    label (length selected)
                    (when selected
                      (format nil "~A:~D-~D" (file-namestring page)
                              (reduce #'min selected :key (lambda (f) (getf f :line)))
                              (reduce #'max selected :key (lambda (f) (getf f :end)))))
                    (and users (length users))
                    (remove-duplicates (mapcar (lambda (f) (getf f :anchor)) users) :test #'equal :from-end t)
                    (and stale (length stale))
                    (reverse kept)
                    (length warnings)
                    (when warnings (substitute #\Space #\Newline (princ-to-string (first warnings))))
                    (/ (- (get-internal-real-time) started) internal-time-units-per-second 1.0)
                    (when failed
                      (let ((*package* (find-package '#:luv-physics)) (*print-case* :downcase))
                        (format nil "~A:~D (~{~S~^ ~})" (file-namestring page) (getf failed :line)
                                (mapcar #'first (form-definitions (getf failed :form))))))
                    (when failure (substitute #\Space #\Newline (princ-to-string failure)))
                    (and (plusp left) left))))
      (format t "~&~A~%" summary)
      summary)))

(defun refresh-page-lines (forms)
  "Give every registered definition the page line of the form of FORMS that defines it now. #OWNJGP"
  (let ((lines (make-hash-table :test 'equal)))
    (dolist (form forms)
      (loop for (name kind) in (form-definitions (getf form :form))
            do (let ((key (list name kind (getf form :anchor))))
                 (unless (gethash key lines) (setf (gethash key lines) (getf form :line))))))
    (dolist (record *definitions*)
      (let ((line (gethash (list (getf record :name) (getf record :kind) (getf record :anchor)) lines)))
        (when line (setf (getf record :org-line) line))))))

(defun reload-section (anchor &key page line)
  "Compile and load the forms of section ANCHOR of PAGE (the loaded page by default), or with LINE
only those of the block holding that page line, with the users they need recompiled; parameters the
user changed keep their values. Print and return one line of summary. #OWNJGP"
  (let* ((started (get-internal-real-time))
         (page (or page *page-pathname*))
         (lines (page-lines-of page))
         (id (string-left-trim "#" (string anchor)))
         (range (find-section lines id))
         (forms (page-forms lines (engine-files)))
         (block (and line (find-if (lambda (b) (<= (third b) line (1+ (fifth b)))) (page-code-blocks lines))))
         (selected (remove-if-not (lambda (form)
                                    (and (equal id (getf form :anchor))
                                         (<= (car range) (getf form :line) (cdr range))
                                         (or (null line) (eql (getf form :block) (third block)))))
                                  forms)))
    (reload-forms selected forms lines page (format nil "reload ~A~@[ (block at line ~D)~]" id line) started)))

(defun tangle-page (page)
  "Tangle PAGE with tools/tangle-page in its directory (Emacs from $EMACS, or emacs); the files
whose text changes are rewritten. Signal an error with the tool's output if it fails. #OWNJGP"
  (let* ((directory (make-pathname :name nil :type nil :version nil :defaults (truename page)))
         (output (make-string-output-stream))
         (process (sb-ext:run-program "tools/tangle-page"
                                      (list (or (sb-ext:posix-getenv "EMACS") "emacs") (file-namestring page))
                                      :directory (namestring directory) :output output :error output
                                      :search nil :wait t)))
    (unless (eql 0 (sb-ext:process-exit-code process))
      (error "luv-physics: tangling ~A failed: ~A" page (get-output-stream-string output)))
    (get-output-stream-string output)))

(defun reload-changed (&key page (tangle t))
  "Tangle PAGE (unless TANGLE is NIL), then compile and load every form of it whose text differs
from the one the image last loaded, with the users they need recompiled, and register the tangled
files again. Print and return one line of summary. #OWNJGP"
  (let* ((started (get-internal-real-time))
         (page (or page *page-pathname*)))
    (when tangle (tangle-page page))
    (let* ((lines (page-lines-of page))
           (files (engine-files))
           (forms (page-forms lines files))
           (table (loaded-forms))
           (changed (loop for form in forms for key in (form-keys forms)
                          unless (equal (getf form :text) (gethash key table)) collect form))
           (summary (reload-forms changed forms lines page
                                  (if tangle "tangle and reload changed" "reload changed") started)))
      (when tangle
        (dolist (file files)
          (register-tangled-file (merge-pathnames file page)))
        (refresh-page-lines forms))
      summary)))
;; Reload a section into the running image:1 ends here

;; [[file:../physics.org::#PYXPDY][Answers for the editor:1]]
(defun editor-page ()
  "For the editor: the page the loaded files were tangled from, as a namestring. #PYXPDY"
  (and *page-pathname* (namestring *page-pathname*)))

(defun editor-definitions (anchor)
  "For the editor: each definition of section ANCHOR as (NAME KIND PAGE-LINE FILE LINE), the name
printed in this package and the kind in lowercase. #PYXPDY"
  (let ((*package* (find-package '#:luv-physics)) (*print-case* :downcase))
    (mapcar (lambda (record)
              (list (prin1-to-string (getf record :name)) (string-downcase (getf record :kind))
                    (getf record :org-line) (getf record :file) (getf record :line)))
            (anchor-definitions anchor))))

(defun editor-page-line (name package)
  "For the editor: (ANCHOR PAGE-LINE PAGE) for the definition of NAME, a symbol as written in a
buffer whose package is named PACKAGE, or NIL when the page defines no such name. #PYXPDY"
  (let* ((*package* (or (find-package (string-upcase (string-left-trim "#:" package)))
                        (find-package '#:cl-user)))
         (*read-eval* nil)
         (symbol (ignore-errors (read-from-string name))))
    (when (and symbol (symbolp symbol))
      (loop for candidate in (list symbol (find-symbol (symbol-name symbol) '#:luv-physics))
            do (multiple-value-bind (anchor line) (and candidate (definition-anchor candidate))
                 (when anchor (return (list anchor line (editor-page)))))))))

(defun editor-section (anchor page)
  "For the editor: what section prints for ANCHOR of PAGE, as a string. #PYXPDY"
  (with-output-to-string (s) (section anchor :page page :stream s)))
;; Answers for the editor:1 ends here

;; [[file:../physics.org::#J0PHYS][Joints against physics:1]]
(defun pendulum-run (degrees seconds &key (length 1.0) world-args)
  "A ball of radius 0.1 on a stiff distance joint of LENGTH to a fixed point, released at rest
DEGREES from the vertical and run SECONDS in open space, in a world of WORLD-ARGS; return its
period, measured between the first and last upward crossings of the vertical, its energy at the
end over its energy at the start, the wall seconds of the steps and the world. #J0PHYS"
  (let* ((w (apply #'make-physics-world :sleep nil world-args))
         (dt (float (physics-world-step-seconds w) 1d0))
         (theta (* degrees (/ pi 180)))
         (ball (add-physics-body w (* length (sin theta)) (- 10 (* length (cos theta))) 0 :radius 0.1 :friction 0))
         (crossings '()) (previous nil))
    (add-physics-joint w :distance ball nil :anchor-b '(0 10 0))
    (flet ((energy ()
             (multiple-value-bind (vx vy vz) (physics-body-velocity w ball)
               (+ (* 0.5d0 (+ (* vx vx) (* vy vy) (* vz vz)))
                  (* 9.81d0 (- (nth-value 1 (physics-body-position w ball)) (- 10 length)))))))
      (let* ((start (energy))
             (wall (drive w seconds
                          (lambda (time)
                            (let ((x (physics-body-position w ball)))
                              (when (and previous (< previous 0) (>= x 0))
                                (push (- time (* dt (/ x (- x previous)))) crossings))
                              (setf previous x))))))
        (values (if (cdr crossings)
                    (/ (- (first crossings) (car (last crossings))) (1- (length crossings)))
                    0d0)
                (/ (energy) start) wall w)))))

(defun elliptic-period (degrees length)
  "The exact period of a simple pendulum of LENGTH released at DEGREES, under g = 9.81. #J0PHYS"
  (let ((k (sin (* degrees (/ pi 360)))) (a 1d0) (b 0d0))
    (setf b (sqrt (- 1 (* k k))))
    (loop repeat 40 do (psetf a (/ (+ a b) 2) b (sqrt (* a b))))
    (* 4 (sqrt (/ length 9.81d0)) (/ pi (* 2 a)))))

(defun spring-run (hertz zeta seconds &key world-args)
  "A ball of 1 kg without gravity on a spring joint of HERTZ and damping ratio ZETA, rest length 1
m, to a fixed point, let go at 1.2 m and run SECONDS in a world of WORLD-ARGS; return its period
between the first and last upward crossings of the rest length, the ratios of each peak past the
rest length to the one before, the wall seconds of the steps and the world. #J0PHYS"
  (let* ((w (apply #'make-physics-world :sleep nil :gravity '(0 0 0) world-args))
         (dt (float (physics-world-step-seconds w) 1d0))
         (ball (add-physics-body w 1.2 0 0 :radius 0.1 :friction 0))
         (xs (make-array (round seconds dt) :element-type 'double-float :initial-element 0d0))
         (k 0) (ups '()) (peaks '()))
    (add-physics-joint w :distance ball nil :anchor-b '(0 0 0) :length 1.0 :hertz hertz :damping-ratio zeta)
    (let ((wall (drive w seconds (lambda (time)
                                   (declare (ignore time))
                                   (setf (aref xs k) (- (physics-body-position w ball) 1d0))
                                   (incf k)))))
      (loop for i from 1 below (1- (length xs))
            for a = (aref xs (1- i)) for x = (aref xs i)
            do (when (and (< a 0) (>= x 0)) (push (* dt (+ i (/ (- a) (- x a)))) ups))
               (when (and (> x 0) (> x a) (>= x (aref xs (1+ i)))) (push x peaks)))
      (setf ups (reverse ups) peaks (reverse peaks))
      (values (if (cdr ups) (/ (- (car (last ups)) (first ups)) (1- (length ups))) 0d0)
              (loop for (p q) on peaks while q collect (/ q p))
              wall w))))

(defun damped-oscillator (hertz zeta)
  "The period of the damped oscillator of HERTZ and damping ratio ZETA and the ratio of each peak
to the one before, as two values. #J0PHYS"
  (let* ((omega (* 2 pi hertz))
         (period (/ (* 2 pi) (* omega (sqrt (- 1 (* zeta zeta)))))))
    (values period (exp (- (* zeta omega period))))))

(defun hanging-chain-stretch (links &key (heavy 1.0) rope (link 0.5) (seconds 5) world-args)
  "The stretch, over its length, of a chain of LINKS balls of 1 kg (the last one HEAVY kg) joined
centre to centre by distance joints of LINK m (ropes when ROPE), hung from a fixed point and run
SECONDS at rest in a world of WORLD-ARGS. #J0PHYS"
  (let* ((w (apply #'make-physics-world :sleep nil world-args))
         (balls (loop for i from 1 to links
                      collect (add-physics-body w 0 (- 20 (* i link)) 0 :radius 0.1 :friction 0
                                                                  :mass (if (= i links) heavy 1.0)))))
    (add-physics-joint w :distance (first balls) nil :anchor-b '(0 20 0) :rope rope)
    (loop for (p q) on balls while q do (add-physics-joint w :distance p q :rope rope))
    (dotimes (i (round seconds (physics-world-step-seconds w))) (step-physics-world w))
    (/ (- (- 20 (nth-value 1 (physics-body-position w (car (last balls))))) (* links link)) (* links link))))

(defun cradle-point (i &optional (top 4.0))
  "The centre of ball I of Newton's cradle on strings hung from the height TOP: the five balls of
radius 0.25 touch along x from 0, each 1 m of string at 30 degrees below TOP, the first (I 0)
drawn back 30 degrees in the plane of swing. #J0PHYS"
  (let ((drop (sqrt 0.75d0)))
    (if (= i 0)
        (values (- (* drop (sin (/ pi 6)))) (- top (* drop (cos (/ pi 6)))) 0d0)
        (values (* i 0.5d0) (- top drop) 0d0))))

(defun hang-cradle (world balls &optional (top 4.0))
  "Hang each of BALLS, the cradle's in order, on two stiff distance joints of 1 m from the points
of height TOP 0.5 m either side of its plane of swing. #J0PHYS"
  (loop for ball in balls for i from 0
        do (dolist (z '(0.5 -0.5))
             (add-physics-joint world :distance ball nil :anchor-b (list (* i 0.5) top z) :length 1.0))))
;; Joints against physics:1 ends here

;; [[file:../physics.org::#J0GR1D][The joint grid, beside Box3D:1]]
(defun joint-grid-world (n &key (kernels :auto))
  "Box3D's joint grid of N x N spheres of radius 0.4 in the plane z = 0, solved by KERNELS: the
sphere of column k and row i at (k, -i, 0) for rows 1 to N-1, each joined by a point joint to the
one above (the fixed point (k, -0.5, 0) for row 1) at anchors (0, 0.5, 0) and (0, -0.5, 0), and to
the one to its left at anchors (-0.5, 0, 0) and (0.5, 0, 0); category 2, a mask without it, and
no sleep. Return the world and the handle of the lowest right-hand sphere. #J0GR1D"
  (let ((w (make-physics-world :sleep nil :kernels kernels))
        (grid (make-array (list n n) :initial-element nil)))
    (dotimes (k n)
      (loop for i from 1 below n
            do (let ((ball (add-physics-body w (float k 1.0) (float (- i) 1.0) 0.0 :radius 0.4
                                               :category 2 :mask #xFFFD)))
                 (setf (aref grid k i) ball)
                 (if (= i 1)
                     (add-physics-joint w :point ball nil :anchor-a '(0 0.5 0) :anchor-b (list (float k 1.0) -0.5 0.0))
                     (add-physics-joint w :point (aref grid k (1- i)) ball :anchor-a '(0 -0.5 0) :anchor-b '(0 0.5 0)))
                 (when (plusp k)
                   (add-physics-joint w :point (aref grid (1- k) i) ball :anchor-a '(0.5 0 0) :anchor-b '(-0.5 0 0))))))
    (values w (aref grid (1- n) (1- n)))))

(defun word-double (word)
  "The number a measuring process printed as WORD, read without evaluation, as a double-float. #J0GR1D"
  (let ((*read-default-float-format* 'double-float) (*read-eval* nil))
    (coerce (read-from-string word) 'double-float)))

(defun joint-grid-lines (command prefix)
  "Run COMMAND, a list of strings, and return its output's lines that begin with PREFIX, as
lists of their words after it. #J0GR1D"
  (loop for line in (uiop:split-string (uiop:run-program command :output :string :error-output *error-output*)
                                       :separator '(#\Newline))
        for words = (remove "" (uiop:split-string line) :test #'string=)
        when (and words (string= (first words) prefix)) collect (rest words)))

(defun run-joint-grid-benchmark (&key (stream *standard-output*) (n 100) (steps 100)
                                      (rounds (let ((r (sb-ext:posix-getenv "ROUNDS")))
                                                (if (and r (plusp (length r))) (parse-integer r) 5))))
  "Print, as an Org table, the CPU time per step of Box3D's joint grid of N x N spheres over STEPS
steps in this engine's kernel families and in Box3D (report/peers/box3d-joint-grid), ROUNDS
rounds of alternating processes, the median of the rounds and each one's ratio to Box3D's, with
the height of the lowest corner at the end. #J0GR1D"
  (let* ((root (namestring (asdf:system-source-directory "luv-physics")))
         (box3d (namestring (merge-pathnames "report/peers/box3d-joint-grid" root)))
         (script (namestring (merge-pathnames "tools/joint-grid-one.lisp" root)))
         (families (available-kernel-families))
         (before (load-average))
         (samples '()))
    (dotimes (round rounds)
      (dolist (words (joint-grid-lines (list "sbcl" "--dynamic-space-size" "4Gb" "--script" script root
                                             (format nil "~{~(~A~)~^,~}" families) (princ-to-string n)
                                             (princ-to-string steps))
                                       "joint-grid"))
        (push (list (format nil "luv-physics ~A" (first words)) (word-double (second words)) (word-double (third words))) samples))
      (dolist (words (joint-grid-lines (list box3d (princ-to-string n) (princ-to-string steps)) "box3d-joint-grid:"))
        ;; n N steps STEPS ms-per-step MS corner-y Y
        (push (list "Box3D, one worker" (word-double (sixth words)) (word-double (eighth words))) samples)))
    (setf samples (reverse samples))
    (let* ((engines (remove-duplicates (mapcar #'first samples) :test #'string= :from-end t))
           (medians (mapcar (lambda (e) (median (mapcar #'second (remove e samples :key #'first :test-not #'string=))))
                            engines))
           (reference (nth (position "Box3D, one worker" engines :test #'string=) medians)))
      (format stream "~&#+caption: Box3D's joint grid, ~D x ~D spheres (~D moving, ~D joints), ~D steps of 1/60 s in 4 ~
                      substeps, no sleep; CPU ms per step, median of ~D rounds of alternating processes; ~
                      Box3D built from its source with -O2 -DNDEBUG, one worker; ~A; load ~A~%"
              n n (* n (1- n)) (+ (* n (1- n)) (* (1- n) (1- n))) steps rounds (cpu-model-name) before)
      (format stream "~&| engine | median ms | lowest | highest | / Box3D | corner y m |~%")
      (format stream "~&|--------+-----------+--------+---------+---------+------------|~%")
      (loop for engine in engines for m in medians
            for rows = (remove engine samples :key #'first :test-not #'string=)
            do (format stream "~&| ~A | ~,2F | ~,2F | ~,2F | ~,2F | ~,3F |~%" engine m
                       (reduce #'min (mapcar #'second rows)) (reduce #'max (mapcar #'second rows))
                       (/ m reference) (third (first rows))))
      (format stream "~&(after the run: load ~A)~%" (load-average)))))
;; The joint grid, beside Box3D:1 ends here

;; [[file:../physics.org::#J0XTRM][Joints at the extremes:1]]
(defun hanging-chain-run (links &key (heavy 1.0) (seconds 20) (link 0.5))
  "A chain of LINKS balls of 1 kg (the last HEAVY kg) joined centre to centre by stiff distance
joints of LINK m, hung from a fixed point, let go at its length and run SECONDS: its stretch over
its length, from the second half of the run, as the mean, the least and the most, then whether
the world stayed finite and valid. #J0XTRM"
  (let* ((w (make-physics-world :sleep nil))
         (balls (loop for i from 1 to links
                      collect (add-physics-body w 0 (- 20 (* i link)) 0 :radius 0.1 :friction 0
                                                                  :mass (if (= i links) heavy 1.0))))
         (last (car (last balls))) (steps (round seconds (physics-world-step-seconds w)))
         (sum 0d0) (count 0) (least most-positive-double-float) (most 0d0))
    (add-physics-joint w :distance (first balls) nil :anchor-b '(0 20 0))
    (loop for (p q) on balls while q do (add-physics-joint w :distance p q))
    (dotimes (i steps)
      (step-physics-world w)
      (when (>= (* 2 i) steps)
        (let ((stretch (/ (- (- 20 (nth-value 1 (physics-body-position w last))) (* links link)) (* links link))))
          (incf sum stretch) (incf count)
          (setf least (min least stretch) most (max most stretch)))))
    (values (/ sum count) least most (and (world-finite-p w) (eq t (validate-physics-world w))))))

(defun soft-chain-law (links &key (heavy 1.0) (link 0.5))
  "The stretch over its length by the soft law of a chain of LINKS balls of 1 kg (the last HEAVY
kg) on stiff joints of LINK m hung at rest in a default world: each joint gives by its load over
its effective mass times the stiff joint's omega squared. #J0XTRM"
  (let* ((w (make-physics-world))
         (omega (* 2 pi (joint-stiffness w (/ (physics-world-step-seconds w) (physics-world-substeps w))))))
    (/ (loop for i from 1 to links
             ;; joint i holds ball i from above: the fixed point or ball i-1, which are 1 kg
             for below = (+ heavy (- links i))
             for upper = (if (= i 1) nil 1d0)
             for lower = (if (= i links) heavy 1d0)
             for mass = (if upper (/ 1 (+ (/ 1 upper) (/ 1 lower))) lower)
             sum (/ (* below 9.81d0) (* mass omega omega)))
       (* links link))))

(defun stretched-pair (&key (steps 10))
  "Two balls of 1 kg 2 m apart in free space joined by a stiff distance joint of 1 m, run STEPS:
its length after steps 1, 5 and STEPS, the fastest either ball moved at the end of a step, and how
far their centre of mass moved. #J0XTRM"
  (let* ((w (make-physics-world :sleep nil :gravity '(0 0 0)))
         (a (add-physics-body w -1.0 5.0 0.0)) (b (add-physics-body w 1.0 5.0 0.0))
         (joint (add-physics-joint w :distance a b :length 1.0))
         (lengths '()) (fastest 0.0))
    (dotimes (i steps)
      (step-physics-world w)
      (setf fastest (max fastest (speed-of w a) (speed-of w b)))
      (when (member (1+ i) (list 1 5 steps)) (push (physics-joint-length w joint) lengths)))
    (values (reverse lengths) fastest
            (let ((xa (multiple-value-list (physics-body-position w a)))
                  (xb (multiple-value-list (physics-body-position w b))))
              (sqrt (reduce #'+ (mapcar (lambda (p q k) (expt (- (* 0.5 (+ p q)) k) 2)) xa xb '(0 5 0))))))))

(defun removal-in-a-handler ()
  "A ball of 10 kg hung by a joint of break force 50 N, stepped once with a handler that, at the
joint's :joint-break, removes the ball and the joint, and once without: what the two removals
signalled, the force of the break, whether the world validates, and whether the two worlds end
with one state hash. #J0XTRM"
  (flet ((hang ()
           (let* ((w (make-physics-world :sleep nil))
                  (ball (add-physics-body w 0 9 0 :mass 10)))
             (values w ball (add-physics-joint w :distance ball nil :anchor-b '(0 10 0) :break-force 50)))))
    (multiple-value-bind (w ball joint) (hang)
      (let ((outcomes '()) (force nil))
        (setf (physics-world-event-handler w)
              (lambda (kind a b x y z speed datum)
                (declare (ignore a b x y z datum))
                (when (eq kind :joint-break)
                  (setf force speed)
                  (dolist (call (list (lambda () (remove-physics-body w ball)) (lambda () (remove-physics-joint w joint))))
                    (push (handler-case (progn (funcall call) :done) (error (e) (type-of e))) outcomes)))))
        (step-physics-world w)
        (let ((plain (hang)))
          (step-physics-world plain)
          (values (reverse outcomes) force (eq t (validate-physics-world w))
                  (= (physics-world-state-hash w) (physics-world-state-hash plain))
                  (physics-body-alive-p w ball)))))))

(defun joint-stability-rows (row)
  "Write the joints' rows of the table of stiff and extreme cases by ROW, the table's function of
a case, whether it held, and a format control and its arguments. #J0XTRM"
  (loop for (links heavy what) in '((20 1000.0 "chain of 20 links of 0.5 m under a 1000 kg ball (1000:1), 20 s")
                                    (200 1.0 "chain of 200 links of 0.5 m, 20 s"))
        do (multiple-value-bind (mean least most ok) (hanging-chain-run links :heavy heavy)
             (let ((law (soft-chain-law links :heavy heavy)))
               (funcall row what (and ok (< (abs (- mean law)) (* 0.1 law)))
                        "stretch over seconds 10 to 20: mean ~,2F % (the soft law ~,2F %), ~,2F to ~,2F %; ~
                         ~:[not finite or invalid~;finite and valid~]"
                        (* 100 mean) (* 100 law) (* 100 least) (* 100 most) ok))))
  (multiple-value-bind (lengths fastest drift) (stretched-pair)
    (funcall row "two balls 2 m apart joined at 1 m, no gravity" (and (< (abs (- (third lengths) 1)) 0.001) (< drift 1e-4))
             "length after 1, 5, 10 steps ~{~,4F~^, ~} m; fastest ~,3F m/s; centre of mass moved ~,1,,,,,'eE m"
             lengths fastest drift))
  (multiple-value-bind (outcomes force valid same alive) (removal-in-a-handler)
    (funcall row "joint's body removed by the :joint-break handler mid-step"
             (and (equal outcomes '(physics-world-busy physics-world-busy)) valid same alive)
             "break at ~,1F N; removing the ball and the joint: ~{~(~A~)~^, ~}; ~:[invalid~;valid~]; ~
              ~:[another state~;the state of the world without the handler~]; the ball ~:[removed~;still there~]"
             force outcomes valid same alive)))
;; Joints at the extremes:1 ends here

;; [[file:../physics.org::#PYR4MD][The large pyramid, beside Box3D:1]]
(defun large-pyramid-world (base &key (kernels :auto) (sleep nil))
  "Box3D's large pyramid of BASE unit cubes at its base, solved by KERNELS: in row i from 0, the
cubes of columns j from i to BASE-1 at ((i + 1)/2 + j - i - BASE/2, i + 1/2, 0), density 100, on a
floor of cells whose top is y = 0, sleeping when SLEEP. Return the world and the top cube's
handle. #PYR4MD"
  (let* ((half (ceiling base 2))
         (terrain (make-voxel-terrain)))
    (fill-terrain terrain (- -4 half) -2 -4 (+ 4 half) (+ base 4) 4 nil)
    (fill-terrain terrain (- -4 half) -2 -4 (+ 4 half) 0 4 t)
    (let ((w (make-physics-world :terrain terrain :sleep sleep :kernels kernels)) (top nil))
      (dotimes (i base)
        (loop for j from i below base
              do (setf top (add-physics-box w (+ (* 0.5 (+ i 1)) (- j i) (* -0.5 base)) (+ i 0.5) 0.0 0.5 0.5 0.5
                                            :density 100))))
      (values w top))))

(defun run-pyramid-benchmark (&key (stream *standard-output*) (base 100) (steps 200) (profile-steps 50)
                                   (rounds (let ((r (sb-ext:posix-getenv "ROUNDS")))
                                             (if (and r (plusp (length r))) (parse-integer r) 5))))
  "Print, as an Org table, the CPU time per step of Box3D's large pyramid of BASE cubes at its base
over STEPS steps in this engine's kernel families and in Box3D (report/peers/box3d-large-pyramid),
ROUNDS rounds of alternating processes, the median of the rounds and each one's ratio to Box3D's,
with the top cube's centre at the end; then the shares of the scalar family's step, by function,
over PROFILE-STEPS steps. #PYR4MD"
  (let* ((root (namestring (asdf:system-source-directory "luv-physics")))
         (box3d (namestring (merge-pathnames "report/peers/box3d-large-pyramid" root)))
         (script (namestring (merge-pathnames "tools/pyramid-one.lisp" root)))
         (families (available-kernel-families))
         (before (load-average))
         (samples '()))
    (dotimes (round rounds)
      (dolist (words (joint-grid-lines (list "sbcl" "--dynamic-space-size" "4Gb" "--script" script root
                                             (format nil "~{~(~A~)~^,~}" families) (princ-to-string base)
                                             (princ-to-string steps))
                                       "pyramid"))
        (push (list (format nil "luv-physics ~A" (first words)) (word-double (second words)) (word-double (third words))
                    (word-double (fourth words)))
              samples))
      (dolist (words (joint-grid-lines (list box3d (princ-to-string base) (princ-to-string steps)) "box3d-large-pyramid:"))
        ;; base B cubes C steps S ms-per-step MS top-y Y top-x X
        (push (list "Box3D, one worker" (word-double (eighth words)) (word-double (tenth words)) (word-double (nth 11 words)))
              samples)))
    (setf samples (reverse samples))
    (let* ((engines (remove-duplicates (mapcar #'first samples) :test #'string= :from-end t))
           (medians (mapcar (lambda (e) (median (mapcar #'second (remove e samples :key #'first :test-not #'string=))))
                            engines))
           (reference (nth (position "Box3D, one worker" engines :test #'string=) medians)))
      (format stream "~&#+caption: Box3D's large pyramid, ~D cubes at the base (~D cubes), ~D steps of 1/60 s in 4 ~
                      substeps, no sleep; CPU ms per step, median of ~D rounds of alternating processes; ~
                      Box3D built from its source with -O2 -DNDEBUG, one worker; ~A; load ~A~%"
              base (/ (* base (1+ base)) 2) steps rounds (cpu-model-name) before)
      (format stream "~&| engine | median ms | lowest | highest | / Box3D | top y m | top x m |~%")
      (format stream "~&|--------+-----------+--------+---------+---------+---------+---------|~%")
      (loop for engine in engines for m in medians
            for rows = (remove engine samples :key #'first :test-not #'string=)
            do (format stream "~&| ~A | ~,2F | ~,2F | ~,2F | ~,2F | ~,3F | ~,3F |~%" engine m
                       (reduce #'min (mapcar #'second rows)) (reduce #'max (mapcar #'second rows))
                       (/ m reference) (third (first rows)) (fourth (first rows))))
      (format stream "~&(after the run: load ~A)~%" (load-average))
      ;; where the step goes: one more process, the scalar family under the statistical profiler
      (let ((shares (joint-grid-lines (list "sbcl" "--dynamic-space-size" "4Gb" "--script" script root "profile"
                                            (princ-to-string base) (princ-to-string profile-steps))
                                      "profile")))
        (format stream "~&~%#+caption: Where the scalar family's step of that pyramid goes: each function holding at ~
                        least 1 % of sb-sprof's samples by itself (1 ms apart) over ~D steps; load ~A~%"
                profile-steps (load-average))
        (format stream "~&| function | share % |~%|----------+---------|~%")
        (dolist (words shares)
          (format stream "~&| ~(~{~A~^ ~}~) | ~A |~%" (butlast words) (car (last words))))))))
;; The large pyramid, beside Box3D:1 ends here

;; [[file:../physics.org::#PYR4MD][The large pyramid, beside Box3D:2]]
(defun run-count-pyramid (&key (stream *standard-output*) (base 40) (from 20) (to 40) counter
                                (families (remove-duplicates (list :scalar (car (last (available-kernel-families)))))))
  "Print, as an Org table, the millions of instructions a step of the pyramid of BASE cubes at
its base (large-pyramid-world) runs in each of FAMILIES: a process of tools/pyramid-one.lisp
stepping it TO times less one stepping it FROM times, over TO - FROM, counted by cachegrind
(count-per-step), with the state hash the longer one ended with. COUNTER, when given, is called
as count-per-step would be, in its place, and nothing is compiled first. #PYR4MD"
  (let ((root (namestring (asdf:system-source-directory "luv-physics"))))
    ;; the engine compiled first, outside valgrind
    (unless counter (against-sample root '(:scalar) 0 0 0))
    (format stream "~&#+caption: Box3D's pyramid, ~D cubes at the base (~D cubes), no sleep; millions of ~
                    instructions a step over steps ~D-~D (cachegrind: a process of ~D steps less one of ~D); ~
                    ~A; load ~A~%"
            base (/ (* base (1+ base)) 2) from to to from (cpu-model-name) (load-average))
    (format stream "~&| family | instructions | state hash |~%|--------+--------------+------------|~%")
    (dolist (family families)
      (multiple-value-bind (per-step hash)
          (funcall (or counter #'count-per-step) "pyramid" from to
                   (lambda (steps)
                     (list root (format nil "hash-~(~A~)" family) (princ-to-string base) (princ-to-string steps))))
        (format stream "~&| ~(~A~) | ~,2F | ~D |~%" family per-step hash)
        (finish-output stream)))
    (format stream "~&(after the run: load ~A)~%" (load-average))))
;; The large pyramid, beside Box3D:2 ends here

;; [[file:../physics.org::#SQU33Z][Squeezed between a box and the cells: the box yields, the cells hold:2]]
(defun deepest-into-cells (terrain x y z r)
  "How deep the surface of a sphere of radius R centred at X Y Z reaches into the solid cells of
TERRAIN around its centre's cell (negative when it touches none). #SQU33Z"
  (let ((deepest -1.0))
    (loop for i from (1- (floor x)) to (1+ (floor x)) do
      (loop for j from (1- (floor y)) to (1+ (floor y)) do
        (loop for k from (1- (floor z)) to (1+ (floor z))
              when (terrain-solid-p terrain i j k)
                do (let ((dx (- (max i (min (1+ i) x)) x)) (dy (- (max j (min (1+ j) y)) y))
                         (dz (- (max k (min (1+ k) z)) z)))
                     (setf deepest (max deepest (- r (sqrt (+ (* dx dx) (* dy dy) (* dz dz))))))))))
    deepest))

(defun depth-into-box (bounds x y z r)
  "How deep the surface of a sphere of radius R centred at X Y Z reaches into the box BOUNDS (a
list x0 y0 z0 x1 y1 z1), and, as a second value, whether the centre lies inside it. #SQU33Z"
  (destructuring-bind (bx0 by0 bz0 bx1 by1 bz1) bounds
    (let ((dx (- (max bx0 (min bx1 x)) x)) (dy (- (max by0 (min by1 y)) y)) (dz (- (max bz0 (min bz1 z)) z)))
      (values (- r (sqrt (+ (* dx dx) (* dy dy) (* dz dz)))) (= 0 dx dy dz)))))

(defun posted-box-bounds (world)
  "The bounds (x0 y0 z0 x1 y1 z1) of the first box posted to WORLD for its next step, where it
will be at that step's end. #SQU33Z"
  (let ((b (physics-world-boxes world)) (dt (/ 1.0 60)))
    (with-box-columns (min-x min-y min-z max-x max-y max-z vx vy vz) b
      (list (+ (aref min-x 0) (* dt (aref vx 0))) (+ (aref min-y 0) (* dt (aref vy 0)))
            (+ (aref min-z 0) (* dt (aref vz 0))) (+ (aref max-x 0) (* dt (aref vx 0)))
            (+ (aref max-y 0) (* dt (aref vy 0))) (+ (aref max-z 0) (* dt (aref vz 0)))))))

(defun squeeze-scene (family scene)
  "Run SCENE (:step, :marbles, :far-step, :wall or :press) under FAMILY for 240 steps of 1/60 s; return the
count of ball positions outside air cells of the resident world or below the floor less a slop,
the lowest centre, the walker's final x and y (NIL for :press), the state hash, the fastest
speed of any ball after any step, the deepest any ball's surface reached into a solid cell and
into the box (its radius, when the centre lies inside), and whether a centre lay inside the box. #SQU33Z"
  ;; the walker's structure is defined with the walker, later on the page
  (declare (notinline physics-player-x physics-player-y))
  (let ((terrain (make-voxel-terrain)))
    (fill-terrain terrain -16 0 -16 16 12 16 nil)
    (fill-terrain terrain -16 -16 -16 16 0 16 t)
    (case scene
      ((:step :marbles) (fill-terrain terrain 6 0 -4 16 1 4 t))
      (:far-step (fill-terrain terrain 8 0 -4 16 1 4 t))
      (:wall (fill-terrain terrain 6 0 -4 16 3 4 t)))
    (let* ((world (make-physics-world :terrain terrain :kernels family))
           (player (make-physics-player 0d0 0d0 0d0))
           (slop *physics-linear-slop*)
           (balls (loop for x from 1.0 to 5.5 by 0.5
                        collect (add-physics-body-of-kind world (if (eq scene :marbles) :marble :ball) x 0.3 0.0)))
           (outside 0) (lowest 100.0) (fastest 0.0) (cells 0.0) (box 0.0) (inside-box nil))
      (dotimes (frame 240)
        (if (eq scene :press)
            (post-physics-box world 3.25 (max 0.7 (- 1.5 (* frame (/ 1.0 60)))) 0.0 2.0 0.5 1.0
                              :vy (if (> (- 1.5 (* frame (/ 1.0 60))) 0.7) -1.0 0.0) :owner :press)
            (progn (advance-physics-player player terrain (/ 1d0 60) :move-x 1d0)
                   (post-physics-player world player)))
        (let ((bounds (posted-box-bounds world)))
          (step-physics-world world)
          (dolist (h balls)
            (multiple-value-bind (x y z) (physics-body-position world h)
              (let ((r (physics-body-radius world h)))
                (multiple-value-bind (vx vy vz) (physics-body-velocity world h)
                  (setf fastest (max fastest (sqrt (+ (* vx vx) (* vy vy) (* vz vz))))))
                (setf cells (max cells (deepest-into-cells terrain x y z r))
                      lowest (min lowest y))
                (multiple-value-bind (depth inside) (depth-into-box bounds x y z r)
                  (setf box (max box depth) inside-box (or inside-box inside)))
                ;; a cell of a chunk that is not resident counts as solid
                (when (or (< y (- slop)) (terrain-solid-p terrain (floor x) (floor y) (floor z)))
                  (incf outside)))))))
      (values outside lowest
              (and (not (eq scene :press)) (physics-player-x player))
              (and (not (eq scene :press)) (physics-player-y player))
              (physics-world-state-hash world)
              fastest cells box inside-box))))
;; Squeezed between a box and the cells: the box yields, the cells hold:2 ends here

;; [[file:../physics.org::#SQU33Z][Squeezed between a box and the cells: the box yields, the cells hold:8]]
(defun squeeze-scene-world (next kernels)
  "A random scene for the squeeze campaign, drawn from the generator NEXT: a world solved by
KERNELS over a floor three cells deep (top at y = 0) with blocks and pits in [-4, 4), and its
bodies of one radius, mass and restitution. Return the world, its terrain, the bodies' handles,
their restitution and the blocks raised, each (x0 z0 x1 top z1): cells x0 <= x < x1, z0 <= z <
z1 solid from the floor up to TOP. #SQU33Z"
  (flet ((pick (lo hi) (+ lo (* (- hi lo) (funcall next))))
         (cell (lo hi) (+ lo (floor (* (- hi lo) (funcall next))))))
    (let ((terrain (make-voxel-terrain)))
      ;; the floor covers its chunks' whole extent: no edge for a body to fall from
      (fill-terrain terrain -16 0 -16 16 16 16 nil)
      (fill-terrain terrain -16 -3 -16 16 0 16 t)
      (let ((blocks '()))
      (dotimes (k (cell 3 9))
        (let ((x (cell -4 3)) (z (cell -4 3)))
          (if (< (funcall next) 0.25)
              (fill-terrain terrain x -1 z (+ x (cell 1 3)) 0 (+ z (cell 1 3)) nil)
              (let ((block (list x z (+ x (cell 1 3)) (cell 1 4) (+ z (cell 1 3)))))
                (destructuring-bind (x0 z0 x1 top z1) block
                  (fill-terrain terrain x0 0 z0 x1 top z1 t))
                (push block blocks)))))
      (let* ((world (make-physics-world :terrain terrain :kernels kernels))
             (r (pick 0.08 0.4)) (e (float (* 0.1 (cell 0 10)) 1.0)) (mu (pick 0.0 0.8))
             (bodies '()))
        (loop repeat 200 while (< (length bodies) (cell 10 31))
              do (let* ((x (pick -4.0 4.0)) (z (pick -4.0 4.0))
                        (top (loop for y from 11 downto -3
                                   when (terrain-solid-p terrain (floor x) y (floor z)) return (1+ y)
                                   finally (return -3)))
                        (y (+ top r 0.01)))
                   (when (and (< y 11) (not (terrain-solid-p terrain (floor x) (floor y) (floor z))))
                     (push (add-physics-body world x y z :radius r :mass 1.0 :restitution e :friction mu) bodies))))
        (values world terrain (nreverse bodies) e (nreverse blocks)))))))

(defun run-squeeze-campaign (&key (seed 1) (scenes 40) (steps 300))
  "Run SCENES random squeeze scenes (squeeze-scene-world) of STEPS steps, the I-th drawn from seed
SEED*1000003+I and solved by the I-th kernel family this CPU runs, in turn. Return a plist of
figures: :scenes, :box-steps, :body-steps, :inside (body positions outside the air of the
resident world after a step), :over (speeds over the scene's energy bound), :worst (the largest
speed over its bound, as a ratio), :fastest (m/s) and :held (bodies stopped at a cell's face). #SQU33Z"
  (let ((box-steps 0) (body-steps 0) (inside 0) (over 0) (worst 0.0) (fastest 0.0) (held 0)
        (g 9.81) (push-max *physics-contact-push-max*))
    (dotimes (i scenes)
      (let* ((next (fixed-sequence (+ (* seed 1000003) i)))
             (families (available-kernel-families))
             (kernels (nth (mod i (length families)) families)))
        (multiple-value-bind (world terrain bodies e) (squeeze-scene-world next kernels)
          (let* ((boxes (loop repeat (+ 1 (floor (* 3 (funcall next))))
                              collect (list (vector (- (* 8 (funcall next)) 4) (+ 0.5 (* 3 (funcall next))) (- (* 8 (funcall next)) 4))
                                            (vector (+ 0.2 (* 1.3 (funcall next))) (+ 0.2 (* 0.8 (funcall next))) (+ 0.2 (* 1.3 (funcall next))))
                                            (vector 0 0 0) 0)))
                 (top 0.0) (fastest-box 0.0) (dt (/ 1.0 60))
                 ;; the top of the highest block
                 (blocks (loop for y from 11 downto 0
                               when (loop for x from -4 below 5 thereis
                                      (loop for z from -4 below 5 thereis (terrain-solid-p terrain x (1- y) z)))
                                 return y
                               finally (return 0))))
            (dotimes (step steps)
              (dolist (b boxes)
                (destructuring-bind (c h v turn) b
                  (when (<= turn step)
                    ;; a new velocity, up to 5 m/s, downward as often as up
                    (let ((speed (* 5 (funcall next))) (ax (- (funcall next) 0.5)) (ay (- (funcall next) 0.5)) (az (- (funcall next) 0.5)))
                      (let ((l (max 1e-6 (sqrt (+ (* ax ax) (* ay ay) (* az az))))))
                        (setf (aref v 0) (* speed (/ ax l)) (aref v 1) (* speed (/ ay l)) (aref v 2) (* speed (/ az l)))))
                    (setf (fourth b) (+ step 10 (floor (* 50 (funcall next))))))
                  ;; the box stays over the blocks and above the floor's bottom
                  (dotimes (k 3)
                    (let ((lo (if (= k 1) (+ -2.5 (aref h 1)) -4.5)) (hi (if (= k 1) 4.0 4.5)))
                      (when (or (and (< (aref c k) lo) (< (aref v k) 0)) (and (> (aref c k) hi) (> (aref v k) 0)))
                        (setf (aref v k) (- (aref v k))))))
                  (post-physics-box world (aref c 0) (aref c 1) (aref c 2) (aref h 0) (aref h 1) (aref h 2)
                                    :vx (aref v 0) :vy (aref v 1) :vz (aref v 2) :owner b)
                  (setf top (max top (+ (aref c 1) (aref h 1)))
                        fastest-box (max fastest-box (sqrt (+ (expt (aref v 0) 2) (expt (aref v 1) 2) (expt (aref v 2) 2)))))
                  (dotimes (k 3) (incf (aref c k) (* dt (aref v k))))
                  (incf box-steps)))
              (step-physics-world world)
              (incf held (physics-world-last-step-held-out-count world))
              (let ((bound2 (+ (expt (+ (* (+ 1 e) fastest-box) push-max) 2) (* 2 g (max top blocks)))))
                (dolist (h bodies)
                  (when (physics-body-alive-p world h)
                    (incf body-steps)
                    (multiple-value-bind (x y z) (physics-body-position world h)
                      ;; a cell of a chunk that is not resident counts as solid
                      (when (terrain-solid-p terrain (floor x) (floor y) (floor z))
                        (incf inside)))
                    (multiple-value-bind (vx vy vz) (physics-body-velocity world h)
                      (let ((s2 (+ (* vx vx) (* vy vy) (* vz vz))))
                        (setf fastest (max fastest (sqrt s2))
                              worst (max worst (sqrt (/ s2 bound2))))
                        (when (> s2 bound2) (incf over))))))))))))
    (list :scenes scenes :box-steps box-steps :body-steps body-steps :inside inside :over over
          :worst worst :fastest fastest :held held)))

(defun print-squeeze-figures (figures seconds stream)
  "Print the FIGURES of a squeeze campaign (run-squeeze-campaign) that took SECONDS as an Org
table. #SQU33Z"
  (format stream "~&| scenes | box-steps | body-steps | outside the air | over the bound | fastest / bound | fastest, m/s | held at a face | seconds |~%|-~%| ~D | ~D | ~D | ~D | ~D | ~,3F | ~,2F | ~D | ~,1F |~%"
          (getf figures :scenes) (getf figures :box-steps) (getf figures :body-steps) (getf figures :inside)
          (getf figures :over) (getf figures :worst) (getf figures :fastest) (getf figures :held) seconds))
;; Squeezed between a box and the cells: the box yields, the cells hold:8 ends here

;; [[file:../physics.org::#M9W5P7][Random operation sequences find what a hostile caller would:1]]
(defparameter +fuzz-bad-values+
  (vector (sb-kernel:make-single-float -4194304) sb-ext:single-float-positive-infinity
          sb-ext:single-float-negative-infinity 1e20 -1e20 3e38 1e-30 -1 0 "x" nil :foo)
  "The arguments a hostile caller passes instead of a good one. #M9W5P7")

(defparameter +fuzz-operation-kinds+
  #(:add :add :add :remove :velocity :box :edit :fill :wake :step :step :step :step :spring :player
    :handler :read)
  "The operations a sequence draws from, each as often as it appears. #M9W5P7")

(defstruct (fuzz-state (:constructor %make-fuzz-state))
  "What a run of a sequence keeps: the world, its terrain, every handle issued (in order), what
each live handle's radius was when added, the spring, the player, and what the checks count. #M9W5P7"
  world terrain
  (issued (make-array 16 :adjustable t :fill-pointer 0))
  (radii (make-hash-table))
  (live (make-hash-table))
  spring player
  (handler-edits 0)
  (conditions (make-hash-table)))

(defun make-fuzz-operation (next)
  "A random operation drawn with NEXT, a function returning doubles in [0,1): a list of the
operation's keyword and its arguments, about one in seven of them hostile. #M9W5P7"
  (labels ((uniform (low high) (+ low (* (- high low) (funcall next))))
           (arg (good)
             (if (< (funcall next) 0.86)
                 good
                 (svref +fuzz-bad-values+ (floor (* (funcall next) (length +fuzz-bad-values+))))))
           (handle () (arg (floor (uniform -1 40)))))
    (let ((kind (svref +fuzz-operation-kinds+ (floor (* (funcall next) (length +fuzz-operation-kinds+))))))
      (ecase kind
        (:add (list :add (arg (uniform 1 11)) (arg (uniform 0.3 4)) (arg (uniform 1 11))
                    :radius (arg (uniform 0.05 0.45)) :mass (arg (uniform 0.1 10))
                    :vx (arg (uniform -5 5)) :vy (arg (uniform -5 5)) :vz (arg (uniform -5 5))
                    :life (if (< (funcall next) 0.2) (arg (uniform 0.1 2)) nil)))
        (:remove (list :remove (handle)))
        (:velocity (list :velocity (handle) (arg (uniform -8 8)) (arg (uniform -8 8)) (arg (uniform -8 8))))
        (:box (list :box (arg (uniform 1 11)) (arg (uniform 0.2 2)) (arg (uniform 1 11))
                    (arg (uniform 0.1 1)) (arg (uniform 0.1 1)) (arg (uniform 0.1 1))
                    :vx (arg (uniform -3 3)) :vy (arg (uniform -3 3)) :vz (arg (uniform -3 3))
                    :owner (if (< (funcall next) 0.5) :pusher nil)))
        (:edit (list :edit (arg (floor (uniform 0 12))) (arg (floor (uniform -1 3))) (arg (floor (uniform 0 12)))
                     (< (funcall next) 0.5) (< (funcall next) 0.5)))
        (:fill (let ((x (floor (uniform 0 10))) (z (floor (uniform 0 10))))
                 (list :fill x (arg -1) z (+ x (floor (uniform 1 3))) (arg (floor (uniform 0 2))) (+ z (floor (uniform 1 3)))
                       (< (funcall next) 0.3))))
        (:wake (list :wake (arg (uniform 0 12)) (arg (uniform -1 3)) (arg (uniform 0 12)) (arg (uniform 0 3))))
        (:step (list :step (if (< (funcall next) 0.5) nil (arg (uniform 0.002 0.05)))))
        (:spring (list :spring))
        (:player (list :player (arg (uniform -1 1)) (arg (uniform -1 1)) (< (funcall next) 0.2)))
        (:handler (list :handler (arg (svref #(nil :add :remove :step :terrain :velocity)
                                             (floor (uniform 0 6))))))
        (:read (list :read (handle)))))))

(defun make-fuzz-sequence (seed length)
  "The LENGTH operations of the sequence of SEED. #M9W5P7"
  (let ((next (fixed-sequence seed)))
    (loop repeat length collect (make-fuzz-operation next))))

(defun make-fuzz-state (&optional (kernels :scalar))
  "A fresh run: a floor world over resident air (cells [-16,32)^3, floor at y in [-1,0)) solved
by the kernel family KERNELS, a fountain spring at cell 8 -1 8, and a player standing at
2 0 9. #M9W5P7"
  (let ((terrain (make-voxel-terrain)))
    (fill-terrain terrain -16 -16 -16 32 32 32 nil)
    (fill-terrain terrain -16 -1 -16 32 0 32 t)
    (%make-fuzz-state :world (make-physics-world :terrain terrain :kernels kernels) :terrain terrain
                      :spring (make-fountain 8 -1 8) :player (make-physics-player 2 0 9))))

(defun fuzz-handle (state index)
  "The INDEX-th handle STATE issued, or INDEX itself (a made-up handle) when there is none. #M9W5P7"
  (let ((issued (fuzz-state-issued state)))
    (if (and (integerp index) (< -1 index (length issued))) (aref issued index) index)))

(defun fuzz-note-body (state handle)
  "Note HANDLE as issued and live, with the radius it reads back now. #M9W5P7"
  (vector-push-extend handle (fuzz-state-issued state))
  (setf (gethash handle (fuzz-state-live state)) t
        (gethash handle (fuzz-state-radii state)) (physics-body-radius (fuzz-state-world state) handle)))

(defun fuzz-handler (state mode)
  "An event handler that, on each event, tries the edit MODE names from inside the step and
counts in STATE each one that was not refused; a terrain edit is allowed (it waits for the
step's end). #M9W5P7"
  (let ((world (fuzz-state-world state)))
    (lambda (kind a b x y z speed datum)
      (declare (ignore kind b y speed datum))
      (let ((refused (handler-case
                         (progn
                           (ecase mode
                             (:add (add-physics-body world 5.5 2.0 5.5))
                             (:remove (remove-physics-body world a))
                             (:step (step-physics-world world))
                             (:velocity (set-physics-body-velocity world a 0 1 0))
                             (:terrain (setf (terrain-solid-p (fuzz-state-terrain state) (floor x) 1 (floor z)) nil)))
                           nil)
                       (physics-world-busy (e) e))))
        (cond (refused (incf (gethash (type-of refused) (fuzz-state-conditions state) 0)))
              ((not (eq mode :terrain)) (incf (fuzz-state-handler-edits state))))))))

(defun fuzz-apply (state operation)
  "Run OPERATION on STATE's world. Return :ok, or the physics-error it signalled. #M9W5P7"
  (let ((world (fuzz-state-world state)) (terrain (fuzz-state-terrain state)))
    (flet ((run (kind args)
             (ecase kind
               (:add (fuzz-note-body state (apply #'add-physics-body world args)))
               (:remove (let ((h (fuzz-handle state (first args))))
                          (remove-physics-body world h)
                          (remhash h (fuzz-state-live state))))
               (:velocity (apply #'set-physics-body-velocity world (fuzz-handle state (first args)) (rest args)))
               (:box (apply #'post-physics-box world args))
               (:edit (destructuring-bind (x y z solid wake) args
                        (setf (terrain-solid-p terrain x y z) solid)
                        (when wake (wake-physics-bodies-near world (+ x 0.5) (+ y 0.5) (+ z 0.5) 1.0))))
               (:fill (apply #'fill-terrain terrain args))
               (:wake (apply #'wake-physics-bodies-near world args))
               (:step (step-physics-world world (first args))
                (map-physics-events (lambda (kind a b x y z speed datum)
                                      (declare (ignore b x y z speed datum))
                                      (when (member kind '(:expired :escaped))
                                        (remhash a (fuzz-state-live state))))
                                    world))
               (:spring (run-physics-springs world (list (fuzz-state-spring state))
                                             (lambda (h) (fuzz-note-body state h))))
               (:player (destructuring-bind (move-x move-z jump) args
                          (step-physics-player (fuzz-state-player state) terrain
                                               :move-x move-x :move-z move-z :jump jump)
                          (post-physics-player world (fuzz-state-player state))))
               (:handler (setf (physics-world-event-handler world)
                               (let ((mode (first args)))
                                 (if (member mode '(:add :remove :step :terrain :velocity))
                                     (fuzz-handler state mode)
                                     mode))))
               (:read (let ((h (fuzz-handle state (first args))))
                        (physics-body-position world h)
                        (physics-body-velocity world h))))))
      (handler-case (progn (run (first operation) (rest operation)) :ok)
        (physics-error (e) e)))))

(defun fuzz-finite-p (world)
  "True when no position, velocity or angular velocity of WORLD's bodies is a NaN or an infinity,
read from the bits, so a NaN is never compared. #M9W5P7"
  (loop for buffer in (list (physics-world-awake world) (physics-world-sleeping world))
        always (with-body-columns (x y z vx vy vz wx wy wz) buffer
                 (loop for column in (list x y z vx vy vz wx wy wz)
                       always (loop for i below (body-columns-length buffer)
                                    never (= 255 (ldb (byte 8 23) (sb-kernel:single-float-bits (aref column i)))))))))

(defun fuzz-fingerprint (state)
  "The counts, the state hash and the posted boxes of STATE's world, as a list. #M9W5P7"
  (let ((world (fuzz-state-world state)))
    (list (physics-world-awake-count world) (physics-world-sleeping-count world)
          (physics-world-state-hash world) (box-columns-length (physics-world-boxes world)))))

(defun fuzz-violation (state before outcome)
  "NIL when STATE's world keeps every promise after an operation that gave OUTCOME, starting
from the fingerprint BEFORE; else a sentence naming the first promise broken. #M9W5P7"
  (let ((world (fuzz-state-world state)))
    (block check
      (flet ((fail (control &rest args) (return-from check (apply #'format nil control args))))
        (when (and (typep outcome 'physics-error) (not (equal before (fuzz-fingerprint state))))
          (fail "a failed operation (~A) changed the world: ~S -> ~S" (type-of outcome) before (fuzz-fingerprint state)))
        (handler-case (validate-physics-world world)
          (physics-world-invalid (e) (fail "~A" e)))
        (loop for h being the hash-keys of (fuzz-state-live state)
              unless (physics-body-alive-p world h) do (fail "live handle ~D is stale" h)
              unless (= (physics-body-radius world h) (gethash h (fuzz-state-radii state)))
                do (fail "handle ~D names another body" h))
        (loop for h across (fuzz-state-issued state)
              when (and (not (gethash h (fuzz-state-live state))) (physics-body-alive-p world h))
                do (fail "removed handle ~D still names a body" h))
        (unless (= (hash-table-count (fuzz-state-live state))
                   (+ (physics-world-awake-count world) (physics-world-sleeping-count world)))
          (fail "~D live handles but ~D bodies" (hash-table-count (fuzz-state-live state))
                (+ (physics-world-awake-count world) (physics-world-sleeping-count world))))
        (unless (fuzz-finite-p world) (fail "a number is not finite"))
        (when (plusp (fuzz-state-handler-edits state))
          (fail "~D edits from an event handler went through" (fuzz-state-handler-edits state)))
        nil))))

(defun run-fuzz-operations (operations &key extra-check (kernels :scalar))
  "Run OPERATIONS on a fresh fuzz state whose world KERNELS solves, checking every promise after
each. Return NIL and the state when all hold; else the index of the first operation after which
one broke, the sentence saying which, and the state. EXTRA-CHECK, a function of the state
returning NIL or a sentence, is checked too. #M9W5P7"
  (let ((state (make-fuzz-state kernels)))
    (loop for operation in operations
          for i from 0
          do (let* ((before (fuzz-fingerprint state))
                    (outcome (handler-case (fuzz-apply state operation)
                               (error (e) (return-from run-fuzz-operations
                                            (values i (format nil "~A signalled ~A: ~A" (first operation) (type-of e) e) state)))))
                    (problem (or (fuzz-violation state before outcome)
                                 (and extra-check (funcall extra-check state)))))
               (when (typep outcome 'physics-error)
                 (incf (gethash (type-of outcome) (fuzz-state-conditions state) 0)))
               (when problem (return-from run-fuzz-operations (values i problem state)))))
    (values nil nil state)))

(defun shrink-fuzz-operations (operations &key extra-check (kernels :scalar))
  "The shortest sequence found by dropping chunks of OPERATIONS, halving in size down to one,
while it still breaks a promise (run-fuzz-operations under KERNELS); OPERATIONS must break
one. #M9W5P7"
  (let ((ops (subseq operations 0 (1+ (run-fuzz-operations operations :extra-check extra-check
                                                                      :kernels kernels)))))
    (loop for size = (max 1 (floor (length ops) 2)) then (max 1 (floor size 2))
          do (loop with start = 0
                   while (< start (length ops))
                   do (let ((fewer (append (subseq ops 0 start) (nthcdr (+ start size) ops))))
                        (if (and fewer (run-fuzz-operations fewer :extra-check extra-check :kernels kernels))
                            (setf ops (subseq fewer 0 (1+ (run-fuzz-operations fewer :extra-check extra-check
                                                                                     :kernels kernels))))
                            (incf start size))))
          until (= size 1))
    ops))

(defun run-fuzz-campaign (&key (seed 1) (sequences 40) (length 100) extra-check (stream *standard-output*))
  "Run SEQUENCES sequences of LENGTH operations, the I-th from seed SEED*1000003+I and solved by
the I-th of the kernel families this CPU runs, in turn; print each failing seed, its family and
its shrunk sequence to STREAM. Return a plist of the figures: :sequences,
:operations, :steps, :failures, :shrunk (the shrunk sequences), :kinds (operations run by kind)
and :conditions (refusals by condition type). #M9W5P7"
  (let ((operations 0) (steps 0) (failures 0) (shrunk '())
        (kinds (make-hash-table)) (conditions (make-hash-table)))
    (dotimes (i sequences)
      (let* ((s (+ (* seed 1000003) i))
             (families (available-kernel-families))
             (kernels (nth (mod i (length families)) families))
             (ops (make-fuzz-sequence s length)))
        (multiple-value-bind (at problem state) (run-fuzz-operations ops :extra-check extra-check :kernels kernels)
          (loop for op in (if at (subseq ops 0 (1+ at)) ops)
                do (incf operations) (incf (gethash (first op) kinds 0))
                   (when (eq (first op) :step) (incf steps)))
          (maphash (lambda (k v) (incf (gethash k conditions 0) v)) (fuzz-state-conditions state))
          (when at
            (incf failures)
            (let ((small (shrink-fuzz-operations ops :extra-check extra-check :kernels kernels)))
              (push small shrunk)
              (format stream "~&seed ~D (~(~S~)) failed after operation ~D: ~A~%shrunk to ~D operations:~%~{  ~S~%~}"
                      s kernels at problem (length small) small))))))
    (flet ((alist (table) (sort (loop for k being the hash-keys of table using (hash-value v) collect (cons k v))
                                #'> :key #'cdr)))
      (list :sequences sequences :operations operations :steps steps :failures failures
            :shrunk (reverse shrunk) :kinds (alist kinds) :conditions (alist conditions)))))

(defun print-fuzz-figures (figures seconds stream)
  "Print the FIGURES of a campaign (run-fuzz-campaign) that took SECONDS as an Org table. #M9W5P7"
  (format stream "~&| sequences | operations | steps | failures | seconds |~%|-~%| ~D | ~D | ~D | ~D | ~,1F |~%~%"
          (getf figures :sequences) (getf figures :operations) (getf figures :steps)
          (getf figures :failures) seconds)
  (format stream "| refused with | times |~%|-~%~:{| ~(~A~) | ~D |~%~}"
          (mapcar (lambda (c) (list (car c) (cdr c))) (getf figures :conditions)))
  (format stream "~&~%| operation | times |~%|-~%~:{| ~(~S~) | ~D |~%~}"
          (mapcar (lambda (c) (list (car c) (cdr c))) (getf figures :kinds))))
;; Random operation sequences find what a hostile caller would:1 ends here

;; [[file:../physics.org::#M9W5P7][Random operation sequences find what a hostile caller would:7]]
(defun run-physics-soak (&key (minutes 5) steps (seed 1) (stream *standard-output*) step-hook)
  "Churn a fuzz world for MINUTES of wall-clock time, or for STEPS steps when STEPS is given: each
step adds a ball, removes one of the oldest when more than 300 live, throws one, posts a walking
box, edits a cell under the pile and lets the spring run. Print to STREAM, at every tenth of the
run (of its time, or of its steps), the seconds, the steps, the bodies and the heap in MB after a
full collection, as an Org table. Return the heap's growth in
bytes from the second row (the first after the churn began) to the last. STEP-HOOK, when given,
is the world's step hook (physics-world-step-hook) throughout. #M9W5P7"
  (let* ((state (make-fuzz-state)) (world (fuzz-state-world state)) (terrain (fuzz-state-terrain state))
         (next (fixed-sequence seed)) (handles (make-array 0 :adjustable t :fill-pointer 0))
         (start (get-internal-real-time)) (span (* minutes 60 internal-time-units-per-second))
         (steps-taken 0) (row 0) (first-heap nil) (last-heap 0))
    (setf (physics-world-step-hook world) step-hook)
    (format stream "~&| seconds | steps | bodies | heap MB |~%|-~%")
    (loop
      (let ((elapsed (- (get-internal-real-time) start)))
        (when (if steps (>= (* 10 steps-taken) (* row steps)) (>= elapsed (* row (/ span 10))))
          (sb-ext:gc :full t)
          (setf last-heap (sb-kernel:dynamic-usage))
          ;; growth is counted from the second row, once the buffers have grown to the churn
          (when (= row 1) (setf first-heap last-heap))
          (format stream "| ~D | ~D | ~D | ~,2F |~%" (round elapsed internal-time-units-per-second) steps-taken
                  (+ (physics-world-awake-count world) (physics-world-sleeping-count world))
                  (/ last-heap 1048576.0))
          (finish-output stream)
          (when (> (incf row) 10) (return (- last-heap first-heap)))))
      (vector-push-extend (add-physics-body world (+ 1 (* 10 (funcall next))) (+ 1 (* 3 (funcall next)))
                                            (+ 1 (* 10 (funcall next))) :radius (+ 0.1 (* 0.3 (funcall next)))
                                            :life (if (< (funcall next) 0.3) 2.0 nil))
                          handles)
      (setf handles (delete-if-not (lambda (h) (physics-body-alive-p world h)) handles))
      (when (> (length handles) 300)
        (remove-physics-body world (aref handles 0))
        (setf handles (delete (aref handles 0) handles)))
      (let ((h (aref handles (floor (* (funcall next) (length handles))))))
        (set-physics-body-velocity world h (- (* 10 (funcall next)) 5) (* 5 (funcall next)) (- (* 10 (funcall next)) 5)))
      (post-physics-box world (+ 1 (mod (* 0.05 steps-taken) 10)) 0.5 5.5 0.5 0.5 0.5 :vx 3.0 :owner :walker)
      (let ((x (floor (* 11 (funcall next)))) (z (floor (* 11 (funcall next)))))
        (setf (terrain-solid-p terrain x 0 z) (< (funcall next) 0.5))
        (wake-physics-bodies-near world (+ x 0.5) 0.5 (+ z 0.5) 1.0))
      (run-physics-springs world (list (fuzz-state-spring state)))
      (step-physics-world world)
      (incf steps-taken))))
;; Random operation sequences find what a hostile caller would:7 ends here

;; [[file:../physics.org::#B3NCHW][What the workers gain:1]]
(defun make-wide-basin-world (count &key (kernels :scalar))
  "A world of COUNT awake balls of the basin's kind on a square floor walled two cells high, wide
enough for eight layers of them at the basin's spacing: the basin's pile, too many to stand in
the basin. #B3NCHW"
  (let* ((across (max 4 (ceiling (sqrt (/ count 8.0)))))
         (side (ceiling (+ 0.6 (* 0.55 across))))
         (terrain (make-voxel-terrain))
         (world (progn (fill-terrain terrain -1 -1 -1 (+ side 1) 16 (+ side 1) nil)
                       (fill-terrain terrain -1 -1 -1 (+ side 1) 0 (+ side 1) t)
                       (fill-terrain terrain -1 0 -1 (+ side 1) 2 0 t)
                       (fill-terrain terrain -1 0 side (+ side 1) 2 (+ side 1) t)
                       (fill-terrain terrain -1 0 0 0 2 side t)
                       (fill-terrain terrain side 0 0 (+ side 1) 2 side t)
                       (make-physics-world :terrain terrain :kernels kernels :sleep nil
                                           :features '(:terrain :body-contacts :friction)))))
    (dotimes (i count world)
      (multiple-value-bind (layer k) (floor i (* across across))
        (multiple-value-bind (row col) (floor k across)
          (add-physics-body world (+ 0.3 (* col 0.55) (* 0.01 (mod i 3))) (+ 0.5 (* layer 0.55))
                            (+ 0.3 (* row 0.55) (* 0.01 (mod i 5)))
                            :radius 0.25 :mass 1.0 :friction 0.6 :restitution 0.0))))))

(defparameter *job-phases*
  '((substep-phase 0 1 2 3 4) (prepare-phase 5 6 15 16 17 18) (store-phase 7) (pair-phase 8 9) (terrain-phase 10)
    (prune-phase 12 19) (grid-phase 13) (finalize-phase 14))
  "Each phase whose loops split, with the jobs ([[#SPL1T5]]) that run inside it. #B3NCHW")

(defun make-bench-basin (count family)
  "The benchmark's basin of COUNT awake balls in FAMILY: the basin, or above 10000 balls the wide
basin. #B3NCHW"
  (if (> count 10000)
      (make-wide-basin-world count :kernels family)
      (make-basin-world count :kernels family)))

(defun measure-workers (count family counts &key (from 60) (to 150))
  "Step basins of COUNT balls in FAMILY, one per worker count of COUNTS, in turn for TO steps;
return the median ms per step over steps FROM..TO of each, the serial share of a one-worker step,
whether all reached one state hash, each phase's serial part of the step, as a list of
(phase share), and the part of the two-worker pool's tuned calls that ran split (0 without one). The serial share is measured on one more basin, stepped in turn with the others,
whose pool of one worker (no thread) runs every pass that splits and times it. #B3NCHW"
  (let* ((worlds (mapcar (lambda (n) (open-world-workers (make-bench-basin count family) n)) counts))
         (probe (make-bench-basin count family))
         (pool (make-worker-pool 1))
         (times (mapcar (lambda (w) (declare (ignore w)) (list nil)) worlds))
         (n (length *physics-phases*))
         (clock (make-array (* 2 n) :element-type 'fixnum :initial-element 0)))
    (setf (physics-world-pool probe) pool (worker-pool-split-rows pool) 0)
    (dotimes (i to)
      (when (= i from)
        (setf (physics-world-phase-clock probe) clock)
        (fill (worker-pool-spent pool) 0)
        (fill (worker-pool-merged pool) 0))
      (step-physics-world probe)
      (loop for w in worlds for cell in times
            do (step-physics-world w)
               (when (>= i from) (push (* 1000 (physics-world-last-step-real-seconds w)) (car cell)))))
    (let* ((total (max 1 (reduce #'+ clock :end n)))
           (parts (loop for phase in *physics-phases* for k from 0
                        collect (list phase
                                      (/ (- (aref clock k)
                                            (loop for j in (rest (assoc phase *job-phases*))
                                                  sum (- (aref (worker-pool-spent pool) j)
                                                         (aref (worker-pool-merged pool) j))))
                                         (float total 1d0)))))
           (hashes (mapcar #'physics-world-state-hash (cons probe worlds)))
           (two (find-if (lambda (w) (= 2 (physics-world-workers w))) worlds))
           (split (if two
                      (let ((p (physics-world-pool two)))
                        (/ (reduce #'+ (worker-pool-splits p)) (float (max 1 (reduce #'+ (worker-pool-calls p))) 1d0)))
                      0d0)))
      (mapc #'close-physics-world worlds)
      (setf (physics-world-pool probe) nil)
      (values (mapcar (lambda (cell) (median (car cell))) times)
              (max 0d0 (reduce #'+ parts :key #'second))
              (= 1 (length (remove-duplicates hashes)))
              parts
              split))))

(defun run-worker-benchmark (&key (sizes '(1000 3000 10000 30000)) (stream *standard-output*))
  "Print, as an Org table, the basin at each of SIZES in every kernel family with one worker,
two, and the machine's cores when more: median ms, speed-up over one worker, the serial share
and Amdahl's bound for two, whether the hashes agree, and the part of two workers' tuned calls
that ran split; with the machine and its load. #B3NCHW"
  (let* ((cores (machine-cores))
         (counts (remove-duplicates (list 1 2 (max 2 cores)))))
    (format stream "~&#+caption: the basin, all awake, 60 Hz, 4 substeps; median of steps 60-150, the worlds stepped in turn; ~A, ~D cores; load ~A at the start~%"
            (cpu-model-name) cores (load-average))
    (format stream "~&| balls | family |~{ ~D w ms |~}~{ ~D w speed-up |~} serial share | bound, 2 w | same hash | split, 2 w | serial, % of the step by phase           |~%"
            counts (rest counts))
    (format stream "~&|-------+--------+~{~*---------+~}~{~*---------------+~}--------------+------------+-----------+------------+----------------------------------------------|~%"
            counts (rest counts))
    (dolist (size sizes)
      (dolist (family (available-kernel-families))
        (multiple-value-bind (ms serial same parts split) (measure-workers size family counts)
          (format stream "~&| ~5D | ~6A |~{ ~8,3F |~}~{ ~13,2Fx |~} ~11,1F% | ~9,2Fx | ~9A | ~9,1F% | ~44A |~%"
                  size (string-downcase family) ms
                  (mapcar (lambda (m) (/ (first ms) m)) (rest ms))
                  (* 100 serial) (/ 1 (+ serial (/ (- 1 serial) 2))) (if same "yes" "NO") (* 100 split)
                  (format nil "~{~A~^ ~}"
                          (loop for (phase share) in (sort (copy-list parts) #'> :key #'second)
                                when (>= share 0.01)
                                  collect (format nil "~(~A~) ~D" (subseq (string phase) 0 (search "-PHASE" (string phase)))
                                                  (round (* 100 share))))))
          (finish-output stream))))
    (format stream "~&load ~A at the end~%" (load-average))))
;; What the workers gain:1 ends here

;; [[file:../physics.org::#SNFUZZ][Damaged snapshots, at random:1]]
;;; damaged snapshots, at random: make fuzz and a short run in the claims

(defun reseal-snapshot (buffer)
  "Write into BUFFER, a snapshot, the checksum of its bytes as they are now, so that a damage
made to them meets the checks past the checksum; return BUFFER. #SNFUZZ"
  (declare (type octets buffer))
  (setf (snap-u64 buffer 24) (snapshot-checksum buffer +snapshot-header-bytes+ (snap-u64 buffer 16)))
  buffer)

(defun fuzz-snapshot (world snapshot count random)
  "Restore into WORLD COUNT damaged copies of SNAPSHOT, drawn from the random state RANDOM: a
bit flipped anywhere; a bit flipped past the header and the copy resealed; or the copy cut
short. After each, WORLD goes back to SNAPSHOT. Return the restores, the refusals, the invalid
worlds (a restore that passed whose world fails validation or then signals in a step, or a
refusal that changed the world) and the crashes (any error that is no physics-error), as a
plist. #SNFUZZ"
  (let ((restored 0) (refused 0) (invalid 0) (crashes 0) (n (length snapshot)))
    (dotimes (k count)
      (let ((b (copy-seq snapshot)) (before (physics-world-state-hash world))
            (awake (physics-world-awake-count world)))
        (ecase (random 3 random)
          (0 (let ((i (random n random))) (setf (aref b i) (logxor (aref b i) (ash 1 (random 8 random))))))
          (1 (let ((i (+ +snapshot-header-bytes+ (random (- n +snapshot-header-bytes+) random))))
               (setf (aref b i) (logxor (aref b i) (ash 1 (random 8 random))))
               (reseal-snapshot b)))
          (2 (setf b (subseq b 0 (random n random)))))
        (handler-case
            (progn (restore-physics-world world b)
                   (incf restored)
                   (handler-case (progn (validate-physics-world world) (step-physics-world world)
                                        (validate-physics-world world))
                     (physics-error () (incf invalid))))
          (physics-snapshot-invalid ()
            (incf refused)
            (unless (and (= before (physics-world-state-hash world)) (= awake (physics-world-awake-count world))
                         (handler-case (validate-physics-world world) (physics-error () nil)))
              (incf invalid)))
          (error () (incf crashes)))
        (restore-physics-world world snapshot)))
    (list :restored restored :refused refused :invalid invalid :crashes crashes)))

(defun run-snapshot-fuzz-campaign (&key (seed 1) (count 2000))
  "Fuzz the snapshots of the five standard scenes at 300 balls, each taken after 2 s, and of the
box tower (snapshot-box-tower) at half a second, COUNT damaged copies each, from SEED; return a
list of (SCENE BYTES . FIGURES). #SNFUZZ"
  (let ((random (sb-ext:seed-random-state seed)))
    (loop for scene in '(:basin :pile :fountain :lava :player :box-tower)
          collect (multiple-value-bind (world script)
                      (if (eq scene :box-tower)
                          (values (snapshot-box-tower :auto) (lambda (i) (declare (ignore i))))
                          (make-scene-world scene :count 300))
                    (dotimes (i (if (eq scene :box-tower) 30 120)) (funcall script i) (step-physics-world world))
                    (multiple-value-bind (buffer size) (snapshot-physics-world world)
                      (let ((snapshot (subseq buffer 0 size)))
                        (list* scene size (fuzz-snapshot world snapshot count random))))))))

(defun print-snapshot-fuzz-figures (rows seconds stream)
  "Print the snapshot fuzz campaign's ROWS as an Org table to STREAM. #SNFUZZ"
  (format stream "| scene | snapshot bytes | damaged copies | restored | refused | invalid worlds | crashes |~%")
  (format stream "|-------+----------------+----------------+----------+---------+----------------+---------|~%")
  (dolist (row rows)
    (destructuring-bind (scene size &key restored refused invalid crashes) row
      (format stream "| ~(~A~) | ~D | ~D | ~D | ~D | ~D | ~D |~%" scene size (+ restored refused crashes)
              restored refused invalid crashes)))
  (format stream "~%~,1F s~%" seconds))
;; Damaged snapshots, at random:1 ends here

;; [[file:../physics.org::#SNCOST][What a snapshot costs:1]]
;;; what a snapshot costs: make bench

(defun snapshot-part-bytes (buffer id)
  "The bytes part ID of the snapshot BUFFER takes, its own header of 8 included, the parts walked
by their own ids; 0 when it has no such part. #SNCOST"
  (loop with at = +snapshot-header-bytes+
        while (< at (snap-u64 buffer 16))
        when (= (snap-u32 buffer at) id) return (+ 8 (snap-u32 buffer (+ at 4)))
        do (incf at (+ 8 (snap-u32 buffer (+ at 4))))
        finally (return 0)))

(defun copy-contact-columns-whole (from to)
  "Copy every column of the contact rows FROM into the contact rows TO, of room enough, whole, as
replace copies them: the least a restore that writes a world's contacts can do. #SNCOST"
  (declare (type contact-columns from to))
  (let ((n (contact-columns-length from)))
    (macrolet ((copy ()
                 `(progn ,@(loop for c in +snapshot-traded-contact-columns+
                                 for reader = (intern (format nil "CONTACT-COLUMNS-~A" c) (symbol-package 'contact-columns))
                                 collect `(replace (,reader to) (,reader from)
                                                   :end2 (* n ,(if (eq c 'geometry) (length +contact-fields+) 1)))))))
      (copy))
    to))

(defun run-snapshot-benchmark (&key (stream *standard-output*) (balls 3000) (rounds 30))
  "Measure snapshots: their size in the BALLS-ball basin, in the settled pile and in the box tower, snapshot plus
restore against a step of the basin, and beside them the basin's contact columns copied whole and
the snapshot's checksum alone, the least a restore does (medians of ROUNDS interleaved rounds), an 8-step rollback at
1000 balls, and the bytes consed; print Org tables to STREAM. #SNCOST"
  (format stream "load average ~A at the start~%~%" (load-average))
  (flet ((median (list) (let ((v (sort (coerce list 'vector) #'<))) (aref v (floor (length v) 2))))
         (ms (f) (let ((t0 (clock-ns))) (funcall f) (* 1d-6 (- (clock-ns) t0)))))
    (let* ((world (make-basin-world balls :kernels :auto))
           (other (make-basin-world balls :kernels :auto))
           (buffer nil) (steps '()) (saves '()) (snaps '()) (restores '()) (copies '()) (sums '())
           (rows (make-contact-columns)))
      (dotimes (i 240) (step-physics-world world))
      (setf buffer (snapshot-physics-world world))
      (restore-physics-world other buffer)
      (contact-columns-ensure-capacity rows (* 2 (contact-columns-length (physics-world-contacts world))))
      (sb-ext:gc :full t)
      (dotimes (k rounds)
        (push (ms (lambda () (step-physics-world world))) steps)
        (push (ms (lambda () (setf buffer (snapshot-physics-world world buffer)) (restore-physics-world other buffer))) saves)
        (push (ms (lambda () (snapshot-physics-world world buffer))) snaps)
        (push (ms (lambda () (restore-physics-world other buffer))) restores)
        (push (ms (lambda () (copy-contact-columns-whole (physics-world-contacts world) rows))) copies)
        (push (ms (lambda () (snapshot-checksum buffer +snapshot-header-bytes+ (snap-u64 buffer 16)))) sums))
      (let* ((size (nth-value 1 (snapshot-physics-world world buffer)))
             (awake (physics-world-awake-count world)) (asleep (physics-world-sleeping-count world))
             (contacts (contact-columns-length (physics-world-contacts world)))
             (consed (let ((b (sb-ext:get-bytes-consed)))
                       (dotimes (i 10) (snapshot-physics-world world buffer) (restore-physics-world other buffer))
                       (- (sb-ext:get-bytes-consed) b))))
        (format stream "| basin of ~D at 4 s | bytes | per awake body | per contact |~%" balls)
        (format stream "|----------------------+-------+----------------+-------------|~%")
        (format stream "| whole snapshot (~D awake, ~D asleep, ~D contacts) | ~D | ~,1F | |~%"
                awake asleep contacts size (/ size (max 1 (+ awake asleep))))
        (format stream "| bodies and materials | ~D | ~,1F | |~%"
                (+ (snapshot-part-bytes buffer 3) (snapshot-part-bytes buffer 4) (snapshot-part-bytes buffer 5))
                (/ (+ (snapshot-part-bytes buffer 3) (snapshot-part-bytes buffer 4) (snapshot-part-bytes buffer 5))
                   (max 1 (+ awake asleep))))
        (format stream "| contacts | ~D | | ~,1F |~%" (snapshot-part-bytes buffer 6)
                (/ (snapshot-part-bytes buffer 6) (max 1 contacts)))
        (format stream "| pair list (~D listed pairs) | ~D | ~,1F | |~%"
                (pair-list-count (physics-world-pair-list world)) (snapshot-part-bytes buffer 7)
                (/ (snapshot-part-bytes buffer 7) (max 1 awake)))
        (format stream "| target: 80 a body and 40 a contact | ~D | 80 | 40 |~%~%" (+ (* 80 (+ awake asleep)) (* 40 contacts)))
        (format stream "| basin of ~D at 4 s, ~D rounds | median ms |~%|---+---|~%" balls rounds)
        (format stream "| a step | ~,3F |~%| snapshot | ~,3F |~%| restore | ~,3F |~%| snapshot and restore | ~,3F |~%| share of a step | ~,1F % |~%| bytes consed by 10 snapshots and restores | ~D |~%"
                (median steps) (median snaps) (median restores) (median saves)
                (* 100 (/ (median saves) (median steps))) consed)
        (format stream "| the contact columns copied whole, alone | ~,3F |~%| the checksum, alone | ~,3F |~%| the two, as a share of a step | ~,1F % |~%~%"
                (median copies) (median sums) (* 100 (/ (+ (median copies) (median sums)) (median steps))))))
    (multiple-value-bind (pile script) (make-scene-world :pile)
      (dotimes (i (* 60 12)) (funcall script i) (step-physics-world pile))
      (multiple-value-bind (buffer size) (snapshot-physics-world pile)
        (declare (ignore buffer))
        (format stream "| settled pile | bodies | asleep | bytes | per body |~%|---+---+---+---+---|~%| 12 s | ~D | ~D | ~D | ~,1F |~%~%"
                (+ (physics-world-awake-count pile) (physics-world-sleeping-count pile))
                (physics-world-sleeping-count pile) size
                (/ size (max 1 (+ (physics-world-awake-count pile) (physics-world-sleeping-count pile)))))))
    (let ((tower (snapshot-box-tower :auto)))
      (dotimes (i 30) (step-physics-world tower))
      (multiple-value-bind (buffer size) (snapshot-physics-world tower)
        (format stream "| box tower at 0.5 s | bodies | boxes | box points | bytes | box part |~%|---+---+---+---+---+---|~%| 5 boxes, 2 balls | ~D | ~D | ~D | ~D | ~D |~%~%"
                (+ (physics-world-awake-count tower) (physics-world-sleeping-count tower))
                (box-set-live (physics-world-box-bodies tower))
                (box-point-columns-length (box-set-points (physics-world-box-bodies tower)))
                size (snapshot-part-bytes buffer 11))))
    (run-rollback-benchmark :stream stream :load nil))
  (format stream "~%load average ~A at the end~%" (load-average)))
;; What a snapshot costs:1 ends here

;; [[file:../physics.org::#SNCOST][What a snapshot costs:2]]
(defun run-rollback-benchmark (&key (stream *standard-output*) (balls 1000) (rounds 20) (load t))
  "Measure an 8-step rollback in the BALLS-ball basin at 2 s, under the widest family: a restore
and eight steps, the median of ROUNDS, against a 60 Hz frame, as an Org table to STREAM, with
the load average the run began and ended with when LOAD. make bench-rollback runs it alone. #SNCOST"
  (when load (format stream "load average ~A at the start~%~%" (load-average)))
  (let* ((world (make-basin-world balls :kernels :auto)) (times '()))
    (dotimes (i 120) (step-physics-world world))
    (let ((buffer (snapshot-physics-world world)))
      (sb-ext:gc :full t)
      (dotimes (k rounds)
        (let ((t0 (clock-ns)))
          (restore-physics-world world buffer)
          (dotimes (j 8) (step-physics-world world))
          (push (* 1d-6 (- (clock-ns) t0)) times))))
    (let ((median (aref (sort (coerce times 'vector) #'<) (floor (length times) 2))))
      (format stream "| rollback at ~D balls (2 s), ~D rounds | median ms | share of a 60 Hz frame |~%|---+---+---|~%| restore and 8 steps | ~,2F | ~D % |~%"
              balls rounds median (round (/ median (/ 1000 60.0) 0.01)))))
  (when load (format stream "~%load average ~A at the end~%" (load-average))))

(defun run-count-snapshots (&key (stream *standard-output*) (rounds 20))
  "Print, as an Org table, the millions of instructions a snapshot and its restore of the
3000-ball basin at 4 s run, and a step of the basin, each counted by valgrind's cachegrind in a
process of the tool tools/snapshot-one.lisp (count-process): a process running ROUNDS rounds
less one running none, over ROUNDS; then the share of a step. #SNCOST"
  (let* ((before (load-average))
         (root (namestring (asdf:system-source-directory "luv-physics")))
         (counts (mapcar #'sb-thread:join-thread
                         (loop for (what n) in `(("none" 0) ("snapshot" ,rounds) ("step" ,rounds))
                               collect (let ((what what) (n n))
                                         (sb-thread:make-thread
                                          (lambda () (values (count-process "snapshot" root what (princ-to-string n))))))))))
    (destructuring-bind (none snapshot step) counts
      (let ((per-round (/ (- snapshot none) (* 1d6 rounds))) (per-step (/ (- step none) (* 1d6 rounds))))
        (format stream "~&#+caption: the 3000-ball basin at 4 s, millions of instructions (cachegrind: a process of ~D rounds less one of none, over ~D), widest family; ~A; load ~A before, ~A after~%"
                rounds rounds (cpu-model-name) before (load-average))
        (format stream "| basin of 3000 at 4 s | M instructions |~%|---+---|~%| snapshot and restore | ~,2F |~%| a step | ~,2F |~%| share of a step | ~,1F % |~%"
                per-round per-step (* 100 (/ per-round per-step)))))))
;; What a snapshot costs:2 ends here

;; [[file:../physics.org::#K5DF9S][Scenes are definitions:1]]
(define-condition unknown-physics-scene (invalid-physics-parameter)
  ((operation :initarg :operation :reader unknown-physics-scene-operation))
  (:report (lambda (c s)
             (format s "~(~A~): there is no scene ~S; the name must be ~A"
                     (unknown-physics-scene-operation c) (invalid-physics-parameter-value c)
                     (invalid-physics-parameter-expected c))))
  (:documentation "A scene name that no define-physics-scene defined; NAME is :scene. #K5DF9S"))

(define-condition invalid-physics-scene-clause (invalid-physics-parameter)
  ((scene :initarg :scene :reader invalid-physics-scene-clause-scene))
  (:report (lambda (c s)
             (format s "define-physics-scene ~S: the clause ~S must be ~A"
                     (invalid-physics-scene-clause-scene c) (invalid-physics-parameter-value c)
                     (invalid-physics-parameter-expected c))))
  (:documentation "A clause of define-physics-scene that is unknown, or not of its shape; NAME is
the clause's keyword, VALUE the clause. #K5DF9S"))

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defparameter *physics-scene-features*
    '(:terrain :body-contacts :boxes :friction :rolling-resistance :restitution :sleep :events :mortal :joints
      :box-bodies)
    "The features a scene may declare it uses. #K5DF9S")

  (defparameter *scene-body-arguments*
    '(:radius :mass :restitution :friction :rolling-resistance :vx :vy :vz :life
      :collide-with-bodies :report-hits)
    "The add-physics-body arguments a scene's bodies and a run's :body-arguments may give. #K5DF9S")

  (defun scene-clause-error (scene clause expected)
    "Signal invalid-physics-scene-clause for CLAUSE of the scene SCENE, which must be EXPECTED. #K5DF9S"
    (error 'invalid-physics-scene-clause :scene scene :value clause :expected expected
                                         :name (if (consp clause) (first clause) clause)))

  (defun scene-arguments (scene clause arguments allowed)
    "ARGUMENTS, a plist of CLAUSE whose keys must be among ALLOWED; or a clause error. #K5DF9S"
    (unless (and (evenp (length arguments))
                 (loop for key in arguments by #'cddr always (member key allowed)))
      (scene-clause-error scene clause (format nil "followed by arguments among ~{~S~^ ~}" allowed)))
    arguments)

  (defun scene-clause-slots (scene clauses)
    "The keyword arguments of make-physics-scene that CLAUSES, the clauses of the scene SCENE,
declare, as forms; or a clause error for the first clause that is not of its shape. #K5DF9S"
    (let ((slots '()) (bodies '()) (actions '()) (body-keys *scene-body-arguments*))
      (dolist (clause clauses)
        (unless (and (consp clause) (keywordp (first clause)) (null (cdr (last clause))))
          (scene-clause-error scene clause "a list headed by a clause's keyword"))
        (destructuring-bind (key &rest rest) clause
          (flet ((once (slot form)
                   (when (getf slots slot)
                     (scene-clause-error scene clause "given once"))
                   (setf (getf slots slot) form))
                 (require-shape (ok expected) (unless ok (scene-clause-error scene clause expected)))
                 (point (p) (and (listp p) (= 3 (length p)) (every #'realp p))))
            (case key
              (:terrain
               (require-shape (and rest (listp (first rest)) (<= (length (first rest)) 1)
                           (every #'symbolp (first rest)) (rest rest))
                      "(:terrain (count) form...), naming at most one variable")
               (let ((count (or (first (first rest)) (gensym "COUNT"))))
                 (once :terrain `(lambda (,count) (declare (ignorable ,count)) ,@(rest rest)))))
              (:world
               (once :world-arguments
                     `(list ,@(scene-arguments scene clause rest
                                               '(:sleep :kernels :step-seconds :substeps :gravity)))))
              (:bodies
               (require-shape (and rest (typep (first rest) '(integer 0))) "(:bodies count :spawn f ...)")
               (let* ((options (scene-arguments scene clause (rest rest)
                                                (list* :spawn :jitter :kind :masses :asleep :half-extents :orientation
                                                       body-keys)))
                      (spawn (getf options :spawn)) (masses (getf options :masses)))
                 (flet ((function-p (f) (or (and f (symbolp f)) (and (consp f) (eq (first f) 'lambda)))))
                   (require-shape (function-p spawn)
                                  "given :spawn, the name of a function of the body's index or a lambda form")
                   (require-shape (or (null masses) (function-p masses))
                                  "given :masses, if at all, the name of a function or a lambda form"))
                 (require-shape (typep (getf options :jitter 0) 'real) "given a real :jitter")
                 (require-shape (or (null (getf options :half-extents))
                                    (and (not (getf options :radius)) (consp (getf options :half-extents))
                                         (eq 'quote (first (getf options :half-extents)))
                                         (point (second (getf options :half-extents)))))
                                "given :half-extents, a quoted list of three reals and no :radius")
                 (push `(make-scene-bodies
                         :count ,(first rest)
                         ;; every spawn is called with the index and the count
                         :spawn ,(if (and (consp spawn) (= 2 (length (second spawn))))
                                     spawn
                                     `(lambda (i n) (declare (ignore n)) (funcall ,(if (symbolp spawn) `#',spawn spawn) i)))
                         :masses ,(if (symbolp masses) (and masses `#',masses) masses)
                         :jitter ,(getf options :jitter) :kind ,(getf options :kind) :asleep ,(getf options :asleep)
                         :arguments (list ,@(loop for (k v) on options by #'cddr
                                                  unless (member k '(:spawn :jitter :kind :masses :asleep))
                                                    append (list k v))))
                       bodies)))
              (:springs (once :springs `(lambda () (list ,@rest))))
              (:joints
               (require-shape (and rest (listp (first rest)) (= 2 (length (first rest)))
                                   (every #'symbolp (first rest)) (rest rest))
                              "(:joints (world bodies) form...), naming two variables")
               (once :joints `(lambda ,(first rest) (declare (ignorable ,@(first rest))) ,@(rest rest))))
              (:player
               (require-shape (and (= 2 (length rest)) (point (first rest)) (symbolp (second rest)))
                      "(:player (x y z) input), INPUT a function's name")
               (once :player `(list (lambda () (make-physics-player ,@(first rest)))
                                    (lambda (step) (,(second rest) step)))))
              (:throw
               (require-shape (and (realp (first rest)) (>= (first rest) 0) (point (second rest)))
                      "(:throw seconds (x y z) argument...)")
               (let ((options (scene-arguments scene clause (cddr rest) (list* :say body-keys))))
                 (destructuring-bind (x y z) (second rest)
                   (push `(make-scene-action
                           :seconds ,(first rest) :text ,(getf options :say)
                           :function (lambda (world shift)
                                       (add-physics-body world (+ ,x shift) ,y ,z
                                                         ,@(loop for (k v) on options by #'cddr
                                                                 unless (eq k :say) append (list k v)))))
                         actions))))
              (:at
               (require-shape (and (realp (first rest)) (>= (first rest) 0) (listp (second rest))
                           (= 1 (length (second rest))) (symbolp (first (second rest))))
                      "(:at seconds (world) form...)")
               (let ((shift (gensym "SHIFT")))
                 (push `(make-scene-action
                         :seconds ,(first rest)
                         :function (lambda (,(first (second rest)) ,shift)
                                     (declare (ignore ,shift))
                                     ,@(cddr rest)))
                       actions)))
              (:seconds
               (require-shape (and (= 1 (length rest)) (realp (first rest)) (plusp (first rest))) "(:seconds s), S > 0")
               (once :seconds (first rest)))
              (:pictures
               (require-shape (every (lambda (s) (and (realp s) (>= s 0))) rest) "(:pictures seconds...)")
               (once :moments `',rest))
              (:features
               (require-shape (and (every (lambda (f) (member f *physics-scene-features*)) rest)
                           (= (length rest) (length (remove-duplicates rest))))
                      (format nil "a list of distinct features among ~{~S~^ ~}" *physics-scene-features*))
               (once :features `',rest))
              (t (scene-clause-error
                  scene clause
                  "one of (:terrain ...) (:world ...) (:bodies ...) (:joints ...) (:springs ...) (:player ...) (:throw ...) (:at ...) (:seconds ...) (:pictures ...) (:features ...)"))))))
      (dolist (needed '(:terrain :seconds :features))
        (unless (getf slots needed)
          (scene-clause-error scene needed "given: every scene declares its terrain, its seconds and its features")))
      (list* :bodies `(list ,@(reverse bodies)) :actions `(list ,@(reverse actions)) slots))))

(defstruct (scene-bodies (:constructor make-scene-bodies (&key count spawn jitter kind arguments masses asleep)))
  "COUNT bodies of a scene at the points (SPAWN i COUNT), of KIND (a keyword of *physics-body-kinds*,
or NIL) with the add-physics-body ARGUMENTS, each point moved by JITTER under a seed, each mass
(MASSES u) when MASSES is given, all put to sleep when ASLEEP. #K5DF9S"
  (count 0 :type (integer 0)) (spawn #'identity :type function) (jitter nil) (kind nil) (arguments '())
  (masses nil) (asleep nil))

(defstruct (scene-action (:constructor make-scene-action (&key seconds text function)))
  "What a scene does at SECONDS: FUNCTION of the world and the run's shift along x, and TEXT, a
line to print when it happens. #K5DF9S"
  (seconds 0) (text nil) (function #'identity :type function))

(defstruct (physics-scene (:constructor make-physics-scene
                              (&key name documentation terrain world-arguments bodies joints springs player
                                    actions seconds moments features)))
  "A scene as define-physics-scene declared it: its NAME and DOCUMENTATION; TERRAIN, a function of
the number of bodies at the start returning the terrain; the WORLD-ARGUMENTS of make-physics-world;
BODIES, a list of scene-bodies; JOINTS, NIL or a function of the world and its bodies' handles
that joins them; SPRINGS, NIL or a function making the list of springs; PLAYER,
NIL or a list of a function making the walker and its input function; ACTIONS, a list of
scene-action; the SECONDS it runs; the MOMENTS of its picture; and the FEATURES it uses. #K5DF9S"
  (name nil :type keyword) (documentation "" :type string) (terrain #'identity :type function)
  (world-arguments '()) (bodies '()) (joints nil) (springs nil) (player nil) (actions '())
  (seconds 1) (moments '()) (features '()))

;; the documentation of the scene's public readers, which defstruct cannot give
(loop for (name text)
        in '((physics-scene-name "The keyword naming SCENE. #K5DF9S")
             (physics-scene-features "The features SCENE declares it uses, a list of keywords. #K5DF9S")
             (physics-scene-seconds "How many seconds SCENE runs. #K5DF9S")
             (physics-scene-moments "The moments, in seconds, SCENE's picture shows. #K5DF9S"))
      do (setf (documentation name 'function) text))

(defvar *physics-scenes* '()
  "The scenes defined by define-physics-scene, in the order first defined. #K5DF9S")

(defun register-physics-scene (scene)
  "Put SCENE into *physics-scenes*, in the place of a scene of its name if there is one; return
its name. #K5DF9S"
  (let ((name (physics-scene-name scene)))
    (setf *physics-scenes*
          (if (find name *physics-scenes* :key #'physics-scene-name)
              (substitute scene name *physics-scenes* :key #'physics-scene-name)
              (append *physics-scenes* (list scene))))
    name))

(defmacro define-physics-scene (name documentation &body clauses)
  "Define the scene NAME, a keyword, described by DOCUMENTATION, from CLAUSES (the table of the
section): the expansion makes a physics-scene of closures and registers it. #K5DF9S"
  (unless (keywordp name) (scene-clause-error name name "a keyword naming the scene"))
  (unless (stringp documentation) (scene-clause-error name documentation "a string describing the scene"))
  `(register-physics-scene
    (make-physics-scene :name ,name :documentation ,documentation
                        ,@(scene-clause-slots name clauses))))

(defun find-physics-scene (name &optional (operation 'find-physics-scene))
  "The scene named NAME, or an unknown-physics-scene naming OPERATION and NAME. #K5DF9S"
  (or (find name *physics-scenes* :key #'physics-scene-name)
      (error 'unknown-physics-scene :operation operation :name :scene :value name
                                    :expected (format nil "one of ~{~S~^ ~}"
                                                      (mapcar #'physics-scene-name *physics-scenes*)))))

(defun physics-scene-text (scene)
  "What SCENE shows: its documentation without the trailing anchor. #K5DF9S"
  (let* ((text (physics-scene-documentation scene))
         (hash (search " #" text :from-end t)))
    (if (and hash (= (length text) (+ hash 8))) (subseq text 0 hash) text)))

(defun fixed-sequence (seed)
  "A function returning doubles in [0,1) from a 48-bit linear congruential generator started at
the integer SEED: the same numbers on every run, whatever CL's random state. #K5DF9S"
  (let ((state (ldb (byte 48 0) seed)))
    (lambda ()
      (setf state (ldb (byte 48 0) (+ (* state 25214903917) 11)))
      (/ (ldb (byte 31 17) state) (float (ash 1 31) 1d0)))))
;; Scenes are definitions:1 ends here

;; [[file:../physics.org::#K5DF9S][Scenes are definitions:3]]
(defun scene-world-arguments (scene overrides)
  "The arguments, after the terrain, with which SCENE's world is made: its :world clause, with
each world argument of OVERRIDES (a plist of a run's options) in place of the scene's; a
:features of T stands for the features SCENE declares. #K5DF9S"
  (let ((arguments (copy-list (physics-scene-world-arguments scene))))
    (loop for (key value) on overrides by #'cddr
          when (member key '(:sleep :kernels :step-seconds :substeps :gravity :features))
            do (setf (getf arguments key)
                     (if (and (eq key :features) (eq value t)) (physics-scene-features scene) value)))
    arguments))

(defun add-scene-bodies (world group count seed &optional overrides)
  "Add to WORLD the first COUNT bodies of GROUP, a scene-bodies, their points jittered by the
fixed sequence of SEED when SEED and the group's jitter are given, their masses drawn from that
sequence (of seed 0 without SEED) when the group has masses, the add-physics-body arguments of
OVERRIDES in place of the group's; asleep, when the group is. #K5DF9S"
  (let* ((jitter (and seed (scene-bodies-jitter group)))
         (masses (scene-bodies-masses group))
         (next (and (or jitter masses) (fixed-sequence (or seed 0))))
         (arguments (let ((kind (scene-bodies-kind group)))
                      ;; the run's overrides first, then the group's own, so that they win over its kind's
                      (append overrides
                              (if kind
                                  (let ((number (physics-kind-number kind world)))
                                    (declare (notinline physics-kind-entry))
                                    (append (scene-bodies-arguments group) (list :kind number)
                                            (rest (physics-kind-entry number))))
                                  (scene-bodies-arguments group))))))
    (dotimes (i count)
      (multiple-value-bind (x y z) (funcall (scene-bodies-spawn group) i count)
        (when jitter
          (incf x (* jitter (- (funcall next) 0.5)))
          (incf z (* jitter (- (funcall next) 0.5))))
        (let ((arguments (if masses (list* :mass (funcall masses (funcall next)) arguments) arguments)))
          ;; a group given half-extents is of boxes ([[#BXR0WS]])
          (if (getf arguments :half-extents)
              (apply #'add-physics-box world x y z
                     (append (getf arguments :half-extents)
                             (loop for (k v) on arguments by #'cddr unless (eq k :half-extents) append (list k v))))
              (apply #'add-physics-body world x y z arguments)))))
    ;; the last awake row is the group's last body, so each goes to sleep from its own row
    (when (scene-bodies-asleep group)
      (loop repeat count do (sleep-physics-body world (1- (physics-world-awake-count world)))))))

(defun scene-script (scene world step-seconds &key (shift 0.0) throw-at stream)
  "The function of a step's number that does, before that step of WORLD, what SCENE does: its due
actions (at THROW-AT seconds, when given, with bodies moved SHIFT metres along x; each action's
line printed to STREAM, when given), its springs and its walker, whose frame is STEP-SECONDS. #K5DF9S"
  (let* ((dt (physics-world-step-seconds world))
         (actions (coerce (sort (mapcar (lambda (a) (cons (round (or throw-at (scene-action-seconds a)) dt) a))
                                        (physics-scene-actions scene))
                                #'< :key #'car)
                          'simple-vector))
         (springs (and (physics-scene-springs scene) (funcall (physics-scene-springs scene))))
         (player (and (physics-scene-player scene) (funcall (first (physics-scene-player scene)))))
         (input (and player (second (physics-scene-player scene))))
         (frame (float step-seconds 1d0))
         (terrain (physics-world-terrain world))
         (next 0))
    (declare (type fixnum next) (type double-float frame))
    (lambda (step)
      (loop while (and (< next (length actions)) (<= (car (svref actions next)) step))
            do (let ((action (cdr (svref actions next))))
                 (funcall (scene-action-function action) world shift)
                 (when (and stream (scene-action-text action))
                   (format stream "~&  -- ~A~%" (scene-action-text action))))
               (incf next))
      (when springs (run-physics-springs world springs))
      (when player
        (multiple-value-bind (move-x move-z) (funcall input step)
          (advance-physics-player player terrain frame :move-x move-x :move-z move-z))
        (post-physics-player world player)))))

(defun make-scene-world (name &rest options &key count seed body-arguments (shift 0.0) throw-at stream
                                                 kernels sleep step-seconds substeps gravity features)
  "Build the world of the scene NAME; return it, its script (the function of the step's number to
call before each step) and the scene. OPTIONS change the run: COUNT, the first body clause's
count; SEED, the seed of the spawn jitter and the masses; BODY-ARGUMENTS, add-physics-body
arguments every body of the clauses takes in place of its own; SHIFT and THROW-AT, where along x and when its actions
act; STREAM, where their lines go; and KERNELS, SLEEP, STEP-SECONDS, SUBSTEPS, GRAVITY and
FEATURES (T for the features the scene declares; every feature when not given), the world's.
#K5DF9S"
  (declare (ignore kernels sleep step-seconds substeps gravity features))
  (let* ((scene (find-physics-scene name 'make-scene-world))
         (groups (physics-scene-bodies scene))
         (counts (loop for group in groups for first = t then nil
                       collect (if (and first count)
                                   (if (typep count '(integer 0))
                                       count
                                       (error 'invalid-physics-parameter :name :count :value count
                                                                         :expected "a count of bodies, 0 or more"))
                                   (scene-bodies-count group))))
         (arguments (progn
                      (unless (and (evenp (length body-arguments))
                                   (loop for key in body-arguments by #'cddr
                                         always (member key *scene-body-arguments*)))
                        (error 'invalid-physics-parameter :name :body-arguments :value body-arguments
                                                          :expected (format nil "a plist of arguments among ~{~S~^ ~}"
                                                                            *scene-body-arguments*)))
                      (scene-world-arguments scene options)))
         (world (apply #'make-physics-world :terrain (funcall (physics-scene-terrain scene) (reduce #'+ counts))
                       arguments)))
    (loop for group in groups for n in counts do (add-scene-bodies world group n seed body-arguments))
    (when (physics-scene-joints scene)
      (funcall (physics-scene-joints scene) world (physics-world-handles world)))
    (values world
            (scene-script scene world (getf arguments :step-seconds 1/60)
                          :shift shift :throw-at throw-at :stream stream)
            scene)))

(defun run-physics-scene (name &rest options &key record (every 1) seconds stream &allow-other-keys)
  "Run the scene NAME for its seconds, or SECONDS, with the OPTIONS of make-scene-world; when
RECORD is true, record it every EVERY steps; when STREAM is given, print to it a line per
simulated second and a summary. Return the world and the recording (or NIL). #K5DF9S"
  (find-physics-scene name 'run-physics-scene)
  (multiple-value-bind (world script scene)
      (apply #'make-scene-world name (loop for (key value) on options by #'cddr
                                           unless (member key '(:record :every :seconds))
                                             append (list key value)))
    (let* ((dt (physics-world-step-seconds world))
           (steps (round (or seconds (physics-scene-seconds scene)) dt))
           (per-second (round 1 dt))
           (recording (and record (start-physics-recording world :every every)))
           (second-ms 0d0) (slowest 0d0))
      (when stream
        (format stream "~&~(~A~): ~D balls, ~,4F s steps, ~D substeps, kernels ~(~A~)~%"
                (physics-scene-name scene)
                (+ (physics-world-awake-count world) (physics-world-sleeping-count world))
                dt (physics-world-substeps world) (class-name (class-of (physics-world-kernels world))))
        (format stream "~&  time   awake sleeping contacts colours  ms/step (mean over the second)~%")
        ;; collect what loading and compiling left behind, so that no step pays for it
        (sb-ext:gc :full t))
      (dotimes (step steps)
        (funcall script step)
        (step-physics-world world)
        (when stream
          (let ((ms (* 1000 (physics-world-last-step-real-seconds world))))
            (incf second-ms ms)
            (setf slowest (max slowest ms)))
          (when (zerop (mod (1+ step) per-second))
            (format stream "~&  ~4D s ~7D ~8D ~8D ~7D ~8,3F~%" (floor (1+ step) per-second)
                    (physics-world-awake-count world) (physics-world-sleeping-count world)
                    (physics-world-last-step-contact-count world) (physics-world-last-step-color-count world)
                    (/ second-ms per-second))
            (setf second-ms 0d0))))
      (when recording (stop-physics-recording world))
      (when stream
        (validate-physics-world world)
        (format stream "~&summary: ~D bodies, ~D awake, ~D asleep after ~D s; slowest step ~,3F ms; ~
                        the world validates; state hash ~D~%"
                (+ (physics-world-awake-count world) (physics-world-sleeping-count world))
                (physics-world-awake-count world) (physics-world-sleeping-count world)
                (or seconds (physics-scene-seconds scene)) slowest (physics-world-state-hash world)))
      (values world recording))))
;; Scenes are definitions:3 ends here

;; [[file:../physics.org::#B4S1NS][The basin:1]]
(defun make-basin-terrain (&key (wall-height 6) (air-height 48))
  "The basin: a floor of cells reaching well past walls one cell thick around an 8 m x 8 m
interior [0,8) x [0,8), walls WALL-HEIGHT cells high, air resident up to AIR-HEIGHT. #B4S1NS"
  (let ((terrain (make-voxel-terrain)))
    (fill-terrain terrain -8 0 -8 16 air-height 16 nil)
    (fill-terrain terrain -8 -1 -8 16 0 16 t)
    (fill-terrain terrain -1 0 -1 9 wall-height 0 t)
    (fill-terrain terrain -1 0 8 9 wall-height 9 t)
    (fill-terrain terrain -1 0 0 0 wall-height 8 t)
    (fill-terrain terrain 8 0 0 9 wall-height 8 t)
    terrain))

(defun basin-spawn-point (i)
  "The centre of the I-th ball of the basin lattice: 14 x 14 per layer at 0.55 m spacing from
0.5 m above the floor upward, jittered by at most 0.025 m per axis, deterministically. #B4S1NS"
  (multiple-value-bind (layer k) (floor i 196)
    (multiple-value-bind (row col) (floor k 14)
      (flet ((jitter (salt)
               ;; a fixed integer hash of (i, salt) mapped into [-0.025, 0.025]
               (let ((h (ldb (byte 32 0) (* (+ (* i 7919) (* salt 104729) 12345) 2654435761))))
                 (* 0.025 (- (* 2.0 (/ (ldb (byte 16 8) h) 65535.0)) 1.0)))))
        (values (+ 0.3 (* col 0.55) (jitter 1))
                (+ 0.5 (* layer 0.55) (jitter 2))
                (+ 0.3 (* row 0.55) (jitter 3)))))))

(define-physics-scene :awake-basin
    "The benchmarks' pile: 1000 balls of radius 0.25 m, mass 1 kg, friction 0.6, restitution 0,
dropped into the basin with sleeping off, so that every ball stays awake; the walls are 30 cells
high when there are more than 3000 balls. #B4S1NS"
  (:terrain (balls) (make-basin-terrain :wall-height (if (> balls 3000) 30 6)))
  (:world :sleep nil :kernels :scalar)
  (:bodies 1000 :spawn basin-spawn-point :jitter 0.02
           :radius 0.25 :mass 1.0 :friction 0.6 :restitution 0.0)
  (:seconds 5)
  (:features :terrain :body-contacts :friction))

(defun make-basin-world (count &key (kernels :scalar) (sleep nil) (step-seconds 1/60) (substeps 4))
  "The world of the awake-basin scene with COUNT balls, solving with KERNELS, letting bodies SLEEP
or not, stepping STEP-SECONDS in SUBSTEPS. #B4S1NS"
  (values (make-scene-world :awake-basin :count count :kernels kernels :sleep sleep
                                         :step-seconds step-seconds :substeps substeps)))
;; The basin:1 ends here

;; [[file:../physics.org::#D3M0SC][The main job:1]]
(define-physics-scene :basin
    "1000 balls dropped into the basin; at 4 s a ball is thrown down into the pile #D3M0SC"
  (:terrain () (make-basin-terrain))
  (:world :sleep t :kernels :auto)
  (:bodies 1000 :spawn basin-spawn-point :jitter 0.02 :radius 0.25 :mass 1.0 :friction 0.6)
  (:throw 4 (1.0 7.5 4.0) :radius 0.25 :mass 1.0 :vx 4.0 :vy -6.0
          :say "a ball is thrown down into the pile at 7 m/s")
  (:seconds 8)
  (:pictures 1 4.3 8)
  (:features :terrain :body-contacts :friction :sleep))

(defun run-default-scene (&key (scene :basin) balls seconds (kernels :auto) (stream *standard-output*))
  "The main job, or the scene SCENE: build it (with BALLS bodies in its first body clause, when
given), run it for its seconds or SECONDS, solving with the kernel family KERNELS (the widest
this CPU runs by default), and print a line per simulated second and a summary. Return the
world. #D3M0SC"
  (values (apply #'run-physics-scene scene :stream stream :kernels kernels :seconds seconds
                 (and balls (list :count balls)))))
;; The main job:1 ends here

;; [[file:../physics.org::#B3NCH5][What a step costs:1]]
(defun cpu-model-name ()
  "The CPU's model name from /proc/cpuinfo, or \"unknown CPU\". #B3NCH5"
  (or (ignore-errors (with-open-file (s "/proc/cpuinfo")
                       (loop for line = (read-line s nil) while line
                             when (search "model name" line)
                               return (string-trim " " (subseq line (1+ (position #\: line)))))))
      "unknown CPU"))

(defun load-average ()
  "The three load averages of /proc/loadavg, as a string, or \"?\". #B3NCH5"
  (or (ignore-errors (with-open-file (s "/proc/loadavg") (subseq (read-line s) 0 14))) "?"))

(defun probe-read-ns (bytes &key (hops 2000000))
  "Nanoseconds per read when HOPS reads chase each other through a cycle over the 64-byte lines
of an array of BYTES, in a fixed random order: the best of five passes. #B3NCH5"
  (let* ((lines (max 2 (floor bytes 64)))
         (next (make-array (* 8 lines) :element-type 'fixnum :initial-element 0))
         (order (make-array lines :element-type 'fixnum))
         (lcg 12345) (best most-positive-fixnum))
    (declare (type fixnum-column next order) (type fixnum best))
    (dotimes (i lines) (setf (aref order i) i))
    ;; a fixed shuffle, so every run walks the same cycle
    (loop for i from (1- lines) downto 1
          do (setf lcg (mod (+ (* lcg 1103515245) 12345) 2147483648))
             (rotatef (aref order i) (aref order (mod lcg (1+ i)))))
    (dotimes (k lines)
      (setf (aref next (* 8 (aref order k))) (* 8 (aref order (mod (1+ k) lines)))))
    (dotimes (pass 5)
      (let ((start (clock-ns)) (at 0))
        (declare (type fixnum at))
        (locally (declare #.+kernel-policy+)
          (dotimes (h hops) (setf at (aref next at))))
        (setf best (min best (- (clock-ns) start)))
        ;; the chase's end is used, so the reads cannot be dropped
        (when (minusp at) (error "probe cycle broken"))))
    (/ best (float hops 1d0))))

(defun machine-probe ()
  "The probe of the machine's state, as a string: ns per chained read over 8 MB and over 32 KB. #B3NCH5"
  (format nil "probe ~,1F ns a read over 8 MB, ~,1F over 32 KB"
          (probe-read-ns (* 8 1024 1024)) (probe-read-ns (* 32 1024))))

(defun median (values)
  "The median of the list of reals VALUES. #B3NCH5"
  (let* ((v (sort (copy-list values) #'<)) (n (length v)))
    (if (oddp n) (nth (floor n 2) v) (/ (+ (nth (1- (floor n 2)) v) (nth (floor n 2) v)) 2))))

(defun measure-basin (count &key (kernels :scalar) (from 120) (to 300))
  "Step the basin scene of COUNT awake balls TO times and return a plist of the mean and median
ms per step over steps FROM..TO, contacts, colours, overflow, bytes consed per step, the deepest
overlap any step left (:deepest), and the mean ms of each phase (:phases, an alist). #B3NCH5"
  (let ((world (make-basin-world count :kernels kernels)) (times '()) (consed 0) (deepest 0.0)
        (clock (make-array (* 2 (length *physics-phases*)) :element-type 'fixnum :initial-element 0)))
    (dotimes (i to)
      (when (= i from) (setf (physics-world-phase-clock world) clock))
      (let ((before (sb-ext:get-bytes-consed)))
        (step-physics-world world)
        (when (>= i from)
          (incf consed (- (sb-ext:get-bytes-consed) before))
          (push (* 1000 (physics-world-last-step-real-seconds world)) times))
        (setf deepest (max deepest (physics-world-max-penetration world)))))
    (list :balls count :kernels kernels
          :mean (/ (reduce #'+ times) (length times)) :median (median times)
          :contacts (physics-world-last-step-contact-count world)
          :colours (physics-world-last-step-color-count world)
          :overflow (physics-world-overflow-count world)
          :consed (round consed (length times)) :deepest deepest
          :phases (loop for phase in *physics-phases* for ns across clock
                        collect (cons phase (/ ns 1d6 (- to from))))
          :phase-bytes (loop for phase in *physics-phases*
                             for k from (length *physics-phases*)
                             collect (cons phase (round (aref clock k) (- to from)))))))

(defparameter +bench-phase-groups+
  '(("wake+grid+pairs" wake-phase grid-phase pair-phase) ("terrain" terrain-phase) ("boxes" box-phase)
    ("prune" prune-phase) ("prepare" prepare-phase) ("substeps" substep-phase)
    ("store" store-phase) ("finalize" reset-phase finalize-phase))
  "How the benchmark groups the phases into columns. #B3NCH5")

(defun run-basin-benchmark (&key (counts '(1000 3000 10000)) (stream *standard-output*))
  "Print, as Org tables, the basin measured at each of COUNTS for every kernel family this CPU
runs, each family's time as a fraction of the scalar family's measured in the same run, and
each phase's share; with the machine's model and load. #B3NCH5"
  (let ((families (available-kernel-families))
        (rows '()))
    (format stream "~&#+caption: basin, 60 Hz, 4 substeps, all awake; steps 120-300; ~A; load ~A; ~A~%"
            (cpu-model-name) (load-average) (machine-probe))
    (format stream "~&| balls | family | mean ms | median ms | / scalar | contacts | colours | overflow | bytes consed/step | deepest m | probe ns |~%")
    (format stream "~&|-------+--------+---------+-----------+----------+----------+---------+----------+-------------------+-----------+----------|~%")
    (dolist (count counts)
      (let ((scalar nil))
        (dolist (family families)
          (let* ((probe (probe-read-ns (* 8 1024 1024) :hops 500000))
                 (m (measure-basin count :kernels family)))
            (unless scalar (setf scalar (getf m :median)))
            (push (list* :probe probe m) rows)
            (format stream "~&| ~5D | ~6A | ~7,3F | ~9,3F | ~8,2F | ~8D | ~7D | ~8D | ~17D | ~9,4F | ~8,1F |~%"
                    count (string-downcase family) (getf m :mean) (getf m :median)
                    (/ (getf m :median) scalar) (getf m :contacts) (getf m :colours)
                    (getf m :overflow) (getf m :consed) (getf m :deepest) probe)
            (finish-output stream)))))
    ;; two tables of the phase groups: mean ms, then bytes consed
    (flet ((phase-table (caption key cell)
             (format stream "~&~%#+caption: ~A~%| balls | family |~{ ~A |~}~%"
                     caption (mapcar #'first +bench-phase-groups+))
             (format stream "~&|-------+--------+~{~A~}~%"
                     (mapcar (lambda (g) (format nil "~A+" (make-string (+ 2 (length (first g))) :initial-element #\-)))
                             +bench-phase-groups+))
             (dolist (m (reverse rows))
               (format stream "~&| ~5D | ~6A |~{ ~A |~}~%" (getf m :balls) (string-downcase (getf m :kernels))
                       (loop for (name . phases) in +bench-phase-groups+
                             collect (format nil cell (length name)
                                             (loop for p in phases sum (cdr (assoc p (getf m key))))))))))
      (phase-table "mean ms per step of each phase group" :phases "~v,3F")
      (phase-table "bytes consed per step by each phase group (sb-ext:get-bytes-consed around each phase)"
                   :phase-bytes "~vD"))
    (print-basin-targets (reverse rows) (car (last families)) stream)))

(defun print-basin-targets (rows widest stream)
  "Print, as an Org table, the step-time targets of this machine against ROWS (the plists of
run-basin-benchmark) for the scalar family and the WIDEST: measured median, target, and
whether it is met; and the wide solve's speed-up over the scalar solve. #B3NCH5"
  (flet ((row (balls family)
           (find-if (lambda (m) (and (= (getf m :balls) balls) (eq (getf m :kernels) family))) rows))
         (substeps (m) (cdr (assoc 'substep-phase (getf m :phases)))))
    (format stream "~&~%#+caption: the targets of this machine, from the run above; after it, ~A~%" (machine-probe))
    (format stream "~&| target | measured | probe ns | met |~%|--------+----------+----------+-----|~%")
    (loop for (balls family limit) in (list (list 3000 :scalar 4.0) (list 3000 widest 1.5) (list 10000 widest 6.0))
          for m = (row balls family)
          when m
            do (format stream "~&| ~D balls, ~(~A~), median <= ~,1F ms | ~,3F ms | ~,1F | ~:[no~;yes~] |~%"
                       balls family limit (getf m :median) (getf m :probe) (<= (getf m :median) limit)))
    (let ((scalar (row 3000 :scalar)) (wide (row 3000 widest)))
      (when (and scalar wide (not (eq widest :scalar)))
        (let ((ratio (/ (substeps scalar) (substeps wide))))
          (format stream "~&| 3000 balls, ~(~A~) substeps >= 3x faster than scalar | ~,2Fx | ~,1F, ~,1F | ~:[no~;yes~] |~%"
                  widest ratio (getf scalar :probe) (getf wide :probe) (>= ratio 3)))))))

(defun measure-steps (world from to &optional before-step)
  "Step WORLD TO times, calling BEFORE-STEP first, when given, with the step's number. Return the
mean ms and the bytes consed per step over steps FROM..TO, BEFORE-STEP's work included. #B3NCH5"
  (let ((ms 0d0) (consed 0))
    (dotimes (i to)
      (let ((before (sb-ext:get-bytes-consed)))
        (when before-step (funcall before-step i))
        (step-physics-world world)
        (when (>= i from)
          (incf consed (- (sb-ext:get-bytes-consed) before))
          (incf ms (* 1000 (physics-world-last-step-real-seconds world))))))
    (values (/ ms (- to from)) (round consed (- to from)))))

(defun measure-settled-pile (&key (balls 1000) (kernels :scalar) (steps 100))
  "Drop BALLS balls of the pile scene into the basin, step until every one sleeps (at most 20 s),
then return the mean ms and bytes consed per step over STEPS more steps, and the steps it
took to settle. #B3NCH5"
  (let ((world (make-scene-world :pile :count balls :kernels kernels))
        (settle 0))
    (loop while (and (plusp (physics-world-awake-count world)) (< settle 1200))
          do (step-physics-world world) (incf settle))
    (multiple-value-bind (mean consed) (measure-steps world 0 steps)
      (list :settle-steps settle :awake (physics-world-awake-count world) :mean mean :consed consed))))

(defun measure-churn (&key (balls 3000) (kernels :scalar) (from 120) (to 300))
  "The awake basin pile of BALLS, where from step FROM on every step removes the oldest ball
and drops a new one in from above, 6 m over the spawn point of the step's number: mean ms and
bytes consed per step over FROM..TO, the world and every handle it was given. #B3NCH5"
  (let* ((world (make-basin-world balls :kernels kernels))
         (handles (make-array balls :adjustable t :fill-pointer t
                                    :initial-contents (physics-world-handles world))))
    (multiple-value-bind (mean consed)
        (measure-steps world from to
                       (lambda (i)
                         (when (>= i from)
                           (remove-physics-body world (aref handles (- i from)))
                           (multiple-value-bind (x y z) (basin-spawn-point (mod i 196))
                             (vector-push-extend (add-physics-body world x (+ y 6.0) z :radius 0.25 :mass 1.0
                                                                                        :friction 0.6)
                                                 handles)))))
      (list :mean mean :consed consed :world world :handles handles))))

(defun make-spread-basin-world (balls kernels)
  "The awake basin pile of BALLS solved by KERNELS with four more balls resting on the floor
outside its walls, one at each far corner; return the world and the four balls' handles. #B3NCH5"
  (let ((world (make-basin-world balls :kernels kernels)))
    (values world
            (loop for (x z) in '((-7.5 -7.5) (15.5 -7.5) (-7.5 15.5) (15.5 15.5))
                  collect (add-physics-body world x 0.25 z :radius 0.25 :mass 1.0 :friction 0.6)))))

(defun measure-spread-basin (&key (balls 3000) (kernels :scalar) (from 120) (to 300)
                                  (cells *physics-dense-grid-cells*))
  "The awake basin pile of BALLS with four more balls resting on the floor outside the walls, one
at each far corner, with *physics-dense-grid-cells* bound to CELLS throughout: mean ms and bytes
consed per step over FROM..TO, whether the awake grid was dense at the end, and its box's cells
per ball. #B3NCH5"
  (let* ((*physics-dense-grid-cells* cells)
         (world (make-spread-basin-world balls kernels)))
    (multiple-value-bind (mean consed) (measure-steps world from to)
      (let ((grid (physics-world-awake-grid world)))
        (list :mean mean :consed consed
              :dense (hash-grid-dense grid)
              :cells-per-ball (round (* (hash-grid-nx grid) (hash-grid-ny grid) (hash-grid-nz grid)) balls))))))

(defun make-basin-fountain ()
  "The fountain of the benchmarks: a fountain spring (make-fountain) in the floor cell at the
middle of the basin, two water drops a step. #B3NCH5"
  (make-fountain 4 -1 4))

(defun measure-fountain (&key (kernels :scalar) (from 300) (to 600))
  "The fountain scene, its spring run before every step: mean ms and bytes consed per step
(spring and step) over FROM..TO, and the drops alive. #B3NCH5"
  (multiple-value-bind (world script) (make-scene-world :fountain :kernels kernels)
    (multiple-value-bind (mean consed) (measure-steps world from to script)
      (list :mean mean :consed consed
            :alive (+ (physics-world-awake-count world) (physics-world-sleeping-count world))))))

(defun run-scene-benchmark (&key (stream *standard-output*))
  "Print, as an Org table, the settled pile, the churning pile and the fountain for every
kernel family this CPU runs, and the spread pile under two dense-grid bounds for the widest. #B3NCH5"
  (format stream "~&#+caption: other scenes; load ~A~%" (load-average))
  (format stream "~&| scene | family | mean ms/step | bytes consed/step | note |~%|-------+--------+------+------+------|~%")
  (let ((families (available-kernel-families)))
  (dolist (family families)
    (let ((m (measure-settled-pile :kernels family)))
      (format stream "~&| 1000 balls settled | ~A | ~,4F | ~D | asleep after ~D steps, ~D awake |~%"
              (string-downcase family) (getf m :mean) (getf m :consed) (getf m :settle-steps) (getf m :awake)))
    (let ((m (measure-churn :kernels family)))
      (format stream "~&| 3000 balls, one replaced a step | ~A | ~,3F | ~D | |~%"
              (string-downcase family) (getf m :mean) (getf m :consed)))
    (let ((m (measure-fountain :kernels family)))
      (format stream "~&| fountain, 2 drops a step | ~A | ~,3F | ~D | ~D drops alive |~%"
              (string-downcase family) (getf m :mean) (getf m :consed) (getf m :alive)))
    (finish-output stream))
  ;; the spread pile, steps 120-300, for the widest family: the default bound of a dense
  ;; grid, then a bound of four cells per ball, under which its grid is hashed
  (let ((family (car (last families))))
    (dolist (cells (list *physics-dense-grid-cells* 4))
      (let ((m (measure-spread-basin :kernels family :cells cells)))
        (format stream "~&| 3000 balls and four far ones, steps 120-300, dense bound ~D | ~A | ~,3F | ~D | grid ~:[hashed~;dense~], ~D cells per ball |~%"
                cells (string-downcase family) (getf m :mean) (getf m :consed) (getf m :dense)
                (getf m :cells-per-ball))
        (finish-output stream))))))
;; What a step costs:1 ends here

;; [[file:../physics.org::#B3NCH5][What a step costs:3]]
(define-physics-scene :sleepers
    "balls of radius 0.25 m asleep, one per 0.6 m square, on a floor beside the basin's east wall,
each resting a slop deep and alone #B3NCH5"
  (:terrain (sleepers)
            (let* ((terrain (make-basin-terrain))
                   (side (ceiling (* 0.6 (max 1 (ceiling (sqrt sleepers)))))))
              (fill-terrain terrain 16 0 0 (+ 17 side) 4 (1+ side) nil)
              (fill-terrain terrain 16 -1 0 (+ 17 side) 0 (1+ side) t)
              terrain))
  (:world :sleep t :kernels :avx2)
  (:bodies 1000 :spawn (lambda (k sleepers)
                         (multiple-value-bind (i j) (floor k (max 1 (ceiling (sqrt sleepers))))
                           (values (+ 16.3 (* 0.6 i)) (- 0.25 *physics-linear-slop*) (+ 0.3 (* 0.6 j)))))
           :radius 0.25 :mass 1.0 :friction 0.6 :asleep t)
  (:seconds 1)
  (:features :terrain :friction :sleep))

(defun sleepers-beside-basin (sleepers &key (kernels :avx2))
  "The world of the scene :sleepers with SLEEPERS balls, solved by KERNELS. #B3NCH5"
  (values (make-scene-world :sleepers :count sleepers :kernels kernels)))

(defun cpu-ms-per-step (world steps)
  "Step WORLD STEPS times; return the processor time this process spent, in ms per step. #B3NCH5"
  (let ((start (get-internal-run-time)))
    (dotimes (i steps) (step-physics-world world))
    (/ (* 1000d0 (- (get-internal-run-time) start)) internal-time-units-per-second steps)))

(defun measure-sleeping-scale (sleepers &key (kernels :avx2))
  "Beside SLEEPERS settled sleepers: the heap's bytes per sleeper after the first step, and after
trim-physics-world by the heap and by the world's own count; then the processor ms per step idle
(nothing awake, 2000 steps), while the 1000 balls of the pile scene fall into the basin, settle
and sleep (600 steps), and after the main job's ball is thrown into that pile (300 steps), with
the entries the sleeping grids built in those 300 steps. #B3NCH5"
  (sb-ext:gc :full t)
  (let* ((before (sb-kernel:dynamic-usage))
         (world (sleepers-beside-basin sleepers :kernels kernels)))
    (step-physics-world world)
    (sb-ext:gc :full t)
    (let ((bytes (- (sb-kernel:dynamic-usage) before)))
      (trim-physics-world world)
      (sb-ext:gc :full t)
      (let ((trimmed (- (sb-kernel:dynamic-usage) before))
            (counted (physics-world-bytes world))
            (idle (cpu-ms-per-step world 2000)))
        (flet ((per-sleeper (b) (if (plusp sleepers) (round b sleepers) 0)))
          ;; the pile scene's balls, then the main job's throw
          (add-scene-bodies world (first (physics-scene-bodies (find-physics-scene :pile))) 1000 nil)
          (let ((settling (cpu-ms-per-step world 600)))
            (funcall (scene-action-function (first (physics-scene-actions (find-physics-scene :basin)))) world 0.0)
            (let* ((work (physics-world-sleeping-grid-work world))
                   (wave (cpu-ms-per-step world 300)))
              (list :sleepers sleepers :idle idle :settling settling :wave wave
                    :wave-grid-entries (- (physics-world-sleeping-grid-work world) work)
                    :bytes-per-sleeper (per-sleeper bytes) :trimmed-per-sleeper (per-sleeper trimmed)
                    :counted-per-sleeper (per-sleeper counted)
                    :awake (physics-world-awake-count world)))))))))

(defun run-sleeping-scale-benchmark (&key (counts '(0 10000 50000 100000 200000)) (stream *standard-output*))
  "Print, as an Org table, what sleepers cost at each of COUNTS: idle, settling and wake-wave ms
per step beside them, each against the same at no sleepers, the entries the sleeping grids built
in the wave, and the bytes per sleeper, untrimmed and trimmed. #B3NCH5"
  (format stream "~&#+caption: sleepers beside the basin, avx2, processor time per step; ~A; load ~A~%"
          (cpu-model-name) (load-average))
  (format stream "~&| sleepers | idle ms/step | settling ms/step | / at 0 | wave ms/step | / at 0 | wave grid entries | bytes per sleeper | trimmed | trimmed, world's count | awake at end |~%")
  (format stream "~&|----------+--------------+------------------+--------+--------------+--------+-------------------+-------------------+---------+------------------------+--------------|~%")
  (let ((base nil))
    (dolist (count counts)
      (let ((m (measure-sleeping-scale count)))
        (unless base (setf base m))
        (format stream "~&| ~D | ~,4F | ~,3F | ~,2F | ~,3F | ~,2F | ~D | ~D | ~D | ~D | ~D |~%"
                count (getf m :idle) (getf m :settling) (/ (getf m :settling) (getf base :settling))
                (getf m :wave) (/ (getf m :wave) (getf base :wave)) (getf m :wave-grid-entries)
                (getf m :bytes-per-sleeper) (getf m :trimmed-per-sleeper) (getf m :counted-per-sleeper)
                (getf m :awake))
        (finish-output stream)))))
;; What a step costs:3 ends here

;; [[file:../physics.org::#B3NCH5][What a step costs:9]]
(defun against-tree (rev directory)
  "The commit REV of this repository unpacked into DIRECTORY/REV/ (once, with git archive), as
a directory pathname. #B3NCH5"
  (unless (every (lambda (c) (or (alphanumericp c) (find c "._-/~^"))) rev)
    (error 'invalid-physics-parameter :name :rev :value rev
                                      :expected "a commit name of letters, digits and ._-/~^"))
  (let* ((here (asdf:system-source-directory "luv-physics"))
         (root (merge-pathnames (format nil "~A/" (substitute #\_ #\/ rev)) directory)))
    (unless (probe-file (merge-pathnames "luv-physics.asd" root))
      (ensure-directories-exist root)
      (let ((archive (merge-pathnames "tree.tar" root)))
        (uiop:run-program (list "git" "-C" (namestring here) "archive" "--output" (namestring archive) rev)
                          :error-output *error-output*)
        (uiop:run-program (list "tar" "-x" "-f" (namestring archive) "-C" (namestring root))
                          :error-output *error-output*)
        (delete-file archive)))
    root))

(defun against-sample (root families balls from to)
  "Run tools/against-one.lisp in a fresh SBCL on the engine in the directory ROOT: the basin of
BALLS balls in each of FAMILIES (keywords), timed over steps FROM..TO. Return its lines as
lists (family median-ms hash); BALLS 0 only loads, and so compiles, that engine. #B3NCH5"
  (let* ((script (merge-pathnames "tools/against-one.lisp" (asdf:system-source-directory "luv-physics")))
         (text (uiop:run-program (list "sbcl" "--dynamic-space-size" "4Gb" "--script" (namestring script)
                                       (namestring root) (format nil "~{~(~A~)~^,~}" families)
                                       (princ-to-string balls) (princ-to-string from) (princ-to-string to))
                                 :output :string :error-output *error-output*)))
    (loop for line in (uiop:split-string text :separator '(#\Newline))
          for words = (remove "" (uiop:split-string line) :test #'string=)
          when (and (= 4 (length words)) (string= (first words) "against"))
            collect (list (intern (string-upcase (second words)) :keyword)
                          (word-double (third words))
                          (parse-integer (fourth words))))))

(defun against-summary (samples)
  "SAMPLES, lists (tree family ms hash) from the rounds, as one entry a family, in the order the
families first appear: (family (tree median lowest highest hash) ...), the trees in the order
they first appear. #B3NCH5"
  (let ((families (remove-duplicates (mapcar #'second samples) :from-end t))
        (trees (remove-duplicates (mapcar #'first samples) :from-end t :test #'equal)))
    (loop for family in families
          collect (cons family
                        (loop for tree in trees
                              for rows = (remove-if-not (lambda (s) (and (equal (first s) tree) (eq (second s) family)))
                                                        samples)
                              when rows
                                collect (let ((ms (mapcar #'third rows)))
                                          (list tree (median ms) (reduce #'min ms) (reduce #'max ms)
                                                (fourth (first rows)))))))))

(defun run-against-benchmark (&key (stream *standard-output*)
                                   (revs (let ((r (sb-ext:posix-getenv "REVS")))
                                           (if (and r (plusp (length r)))
                                               (remove "" (uiop:split-string r) :test #'string=)
                                               '("ce415a5"))))
                                   (rounds (let ((r (sb-ext:posix-getenv "ROUNDS")))
                                             (if (and r (plusp (length r))) (parse-integer r) 5)))
                                   (balls 3000) (from 120) (to 300)
                                   (families (available-kernel-families))
                                   (directory (merge-pathnames "report/against/"
                                                               (asdf:system-source-directory "luv-physics"))))
  "Print, as an Org table, the basin's step in this page's engine and in the engines of the
commits REVS, measured in ROUNDS rounds of alternating processes (against-sample), with the
load before and after. #B3NCH5"
  (let* ((trees (append (mapcar (lambda (rev) (cons rev (against-tree rev directory))) revs)
                        (list (cons "this page" (asdf:system-source-directory "luv-physics")))))
         (before (load-average))
         (samples '()))
    (dolist (tree trees) (against-sample (cdr tree) families 0 0 0))
    (dotimes (round rounds)
      (dolist (tree (if (evenp round) trees (reverse trees)))
        (dolist (line (against-sample (cdr tree) families balls from to))
          (push (cons (car tree) line) samples))))
    (format stream "~&#+caption: the ~D-ball basin, CPU ms a step over steps ~D-~D, median of ~D rounds of ~
                    alternating processes (lowest-highest); ~A; load ~A before, ~A after~%"
            balls from to rounds (cpu-model-name) before (load-average))
    (print-against-table (against-summary (reverse samples)) to stream)))

(defun print-against-table (summary steps stream &key (ranges t))
  "Print SUMMARY (against-summary) as the rows of an Org table: per family each tree's median
with its (lowest-highest) when RANGES, then every tree after the first over the first; and the
state hashes after STEPS steps. #B3NCH5"
  (let ((trees (mapcar #'first (rest (first summary)))))
    (format stream "~&| family | ~{~A~^ | ~} | ~{~A / ~A~^ | ~} |~%" trees
            (loop for tree in (rest trees) append (list tree (first trees))))
    (format stream "~&|--------+~{~A~^+~}|~%" (loop repeat (1- (* 2 (length trees))) collect "--------"))
    (loop for (family . rows) in summary
          for base = (second (first rows))
          do (format stream "~&| ~(~A~) | ~{~A~^ | ~} | ~{~A~^ | ~} |~%" family
                     (loop for (nil median low high) in rows
                           collect (if ranges
                                       (format nil "~,3F (~,3F-~,3F)" median low high)
                                       (format nil "~,3F" median)))
                     (loop for (nil median) in (rest rows) collect (format nil "~,3F" (/ median base)))))
    (format stream "~&state hash after ~D steps:~{ ~A ~D~^,~}~%" steps
            (loop for (tree nil nil nil hash) in (rest (first summary)) append (list tree hash)))))
;; What a step costs:9 ends here

;; [[file:../physics.org::#B3NCH5][What a step costs:12]]
(defun cachegrind-instructions (text)
  "The instructions a program ran, read from TEXT, what valgrind's cachegrind wrote to its
standard error: the number after 'I refs:', its commas dropped; NIL when TEXT has no such line.
#B3NCH5"
  (loop for line in (uiop:split-string text :separator '(#\Newline))
        for words = (remove "" (uiop:split-string line) :test #'string=)
        for at = (position "refs:" words :test #'string=)
        when (and at (plusp at) (string= (nth (1- at) words) "I") (nth (1+ at) words))
          do (return (values (parse-integer (remove #\, (nth (1+ at) words)) :junk-allowed t)))))

(defun count-process (script &rest arguments)
  "Run the tool tools/SCRIPT-one.lisp of this tree in a fresh SBCL under valgrind's cachegrind
with ARGUMENTS, no collection starting in it (a collection's signals stop a program under
valgrind). Return the instructions the whole process ran and the state hash ending the first
line it printed that begins with SCRIPT (against, feature). #B3NCH5"
  (let ((path (merge-pathnames (format nil "tools/~A-one.lisp" script) (asdf:system-source-directory "luv-physics"))))
    (multiple-value-bind (out err code)
        (uiop:run-program (list* "env" (format nil "AGAINST_NURSERY_BYTES=~D" (* 12 1024 1024 1024))
                                 "valgrind" "--tool=cachegrind" "--cache-sim=no" "--cachegrind-out-file=/dev/null"
                                 "sbcl" "--dynamic-space-size" "16Gb" "--script" (namestring path) arguments)
                          :output :string :error-output :string :ignore-error-status t)
      (let ((count (cachegrind-instructions err))
            (words (loop for line in (uiop:split-string out :separator '(#\Newline))
                         for words = (remove "" (uiop:split-string line) :test #'string=)
                         when (and words (string= (first words) script)) return words)))
        (unless (and (eql code 0) count words)
          (error "count-process: no count from ~A ~{~A~^ ~} (exit ~A):~%~A" script arguments code
                 (subseq err (max 0 (- (length err) 2000)))))
        (values count (parse-integer (car (last words))))))))

(defun count-per-step (script from to arguments)
  "The millions of instructions one step runs in the process of the tool SCRIPT (count-process)
whose arguments for a run of STEPS steps are (funcall ARGUMENTS STEPS): a run of TO steps less
a run of FROM, the two side by side, over TO - FROM; and the state hash the longer run printed.
#B3NCH5"
  (let ((early (sb-thread:make-thread
                (lambda () (values (apply #'count-process script (funcall arguments from)))))))
    (multiple-value-bind (late hash) (apply #'count-process script (funcall arguments to))
      (values (/ (- late (sb-thread:join-thread early)) (* 1d6 (- to from))) hash))))

(defun run-count-against (&key (stream *standard-output*)
                                (revs (let ((r (sb-ext:posix-getenv "REVS")))
                                        (if (and r (plusp (length r)))
                                            (remove "" (uiop:split-string r) :test #'string=)
                                            '("ce415a5"))))
                                (balls 3000) (from 120) (to 300)
                                (families (available-kernel-families))
                                (directory (merge-pathnames "report/against/"
                                                            (asdf:system-source-directory "luv-physics"))))
  "Print, as an Org table, the millions of instructions a step of the basin runs in this page's
engine and in the engines of the commits REVS, per family: a process's count stepping TO times
less one's stepping FROM times (count-per-step); with each engine's state hash. #B3NCH5"
  (let ((trees (append (mapcar (lambda (rev) (cons rev (against-tree rev directory))) revs)
                       (list (cons "this page" (asdf:system-source-directory "luv-physics")))))
        (before (load-average)))
    ;; every engine compiled first, outside valgrind
    (dolist (tree trees) (against-sample (cdr tree) families 0 0 0))
    (let ((summary
            (loop for family in families
                  collect (cons family
                                (loop for (name . root) in trees
                                      collect (multiple-value-bind (per-step hash)
                                                  (count-per-step "against" from to
                                                                  (lambda (steps)
                                                                    ;; tools/against-one.lisp times the last step
                                                                    (list (namestring root) (string-downcase family)
                                                                          (princ-to-string balls)
                                                                          (princ-to-string (1- steps))
                                                                          (princ-to-string steps))))
                                                (list name per-step per-step per-step hash)))))))
      (format stream "~&#+caption: the ~D-ball basin, millions of instructions a step over steps ~D-~D ~
                      (cachegrind: a process of ~D steps less one of ~D); ~A; load ~A before, ~A after~%"
              balls from to to from (cpu-model-name) before (load-average))
      (print-against-table summary to stream :ranges nil))))
;; What a step costs:12 ends here

;; [[file:../physics.org::#FBNCH9][What leaving features out saves:1]]
(defparameter +feature-scenes+
  '((:fountain "water fountain, drops meet terrain only" (:terrain :friction :sleep :mortal) 300 600)
    (:dead-pile "1000 dead balls: no restitution, rolling, events" (:terrain :body-contacts :friction) 120 300)
    (:basin "1000-ball basin pile, every feature" nil 120 300)
    (:walker "walker among the fountain's drops, no body contacts" (:terrain :boxes :friction :sleep :mortal)
     300 600))
  "The scenes of the feature benchmark: each a keyword, what it is, its features (NIL for every
feature) and the steps FROM and TO it is measured over. The piles run without sleep, as the
basin benchmark's do, so all their balls are awake while they are measured. #FBNCH9")

(defun feature-scene (name &key (kernels :auto) (features +physics-features+) (balls 1000)
                             (sleep (not (member name '(:dead-pile :basin)))))
  "The world of the feature scene NAME of +feature-scenes+ with FEATURES, solved by KERNELS (a
pile holds BALLS balls; SLEEP, whether its bodies may sleep, is false for the piles), and the
function of the step's number to call before each step, as the first two values of
make-scene-world. The piles are the scene
:awake-basin, the fountain the scene :fountain and the walker among the drops the scene :walker.
#FBNCH9"
  (ecase name
    ((:dead-pile :basin)
     (make-scene-world :awake-basin :count balls :kernels kernels :sleep sleep :features features))
    ((:fountain :walker) (make-scene-world name :kernels kernels :sleep sleep :features features))))

(define-physics-scene :walker
    "the walker among the fountain's drops: it meets drops, they meet no body #FBNCH9"
  (:terrain () (make-basin-terrain))
  (:world :sleep t :kernels :auto)
  (:springs (make-basin-fountain))
  (:player (3d0 0d0 3d0) player-scene-input)
  (:seconds 10)
  (:features :terrain :boxes :friction :sleep :mortal))

(defun measure-feature-scene (name &key (kernels :auto))
  "Step the feature scene NAME built general and specialised, in turn, and return a plist of the
median ms and the bytes consed per step of each over its steps FROM..TO. #FBNCH9"
  (destructuring-bind (what features from to) (rest (assoc name +feature-scenes+))
    (declare (ignore what))
    (multiple-value-bind (general general-step) (feature-scene name :kernels kernels)
      (multiple-value-bind (special special-step)
          (feature-scene name :kernels kernels :features (or features +physics-features+))
        (let ((ms (list '() '())) (consed (list 0 0)))
          (dotimes (i to)
            (flet ((one (k world before)
                     (when before (funcall before i))
                     (let ((bytes (sb-ext:get-bytes-consed)))
                       (step-physics-world world)
                       (when (>= i from)
                         (incf (nth k consed) (- (sb-ext:get-bytes-consed) bytes))
                         (push (* 1000 (physics-world-last-step-real-seconds world)) (nth k ms))))))
              (if (evenp i)
                  (progn (one 0 general general-step) (one 1 special special-step))
                  (progn (one 1 special special-step) (one 0 general general-step)))))
          (let ((n (- to from)))
            (list :general (median (first ms)) :specialised (median (second ms))
                  :general-consed (round (first consed) n) :specialised-consed (round (second consed) n)
                  ;; a constraint's floats: its main block's and its side block's
                  :general-block (let ((c (physics-world-constraints general)))
                                   (+ (constraint-columns-block c) (constraint-columns-side-block c)))
                  :specialised-block (let ((c (physics-world-constraints special)))
                                       (+ (constraint-columns-block c) (constraint-columns-side-block c)))
                  :bodies (+ (physics-world-awake-count special) (physics-world-sleeping-count special)))))))))

(defun run-feature-benchmark (&key (stream *standard-output*) (kernels :auto))
  "Print, as an Org table, each scene of +feature-scenes+ under the general step and the step
built for its features, in one run, with the machine's load. #FBNCH9"
  (let ((body-bytes (+ +body-columns-row-bytes+ (* 2 4 +solver-stride+))))
    (format stream "~&#+caption: general and specialised steps, ~(~A~) family; load ~A~%" kernels (load-average))
    (format stream "~&| scene | bodies | general median ms | specialised median ms | ratio | bytes consed/step | column bytes/body | column bytes/contact |~%")
    (format stream "~&|-------+--------+------------+----------------+-------+-------------------+-------------------+----------------------|~%")
    (dolist (scene +feature-scenes+)
      (let ((m (measure-feature-scene (first scene) :kernels kernels)))
        (flet ((contact-bytes (block)
                 ;; the persistent row, the constraint's floats and its three fixnums
                 (+ +contact-columns-row-bytes+ (* 4 (floor block 8)) (* 3 8))))
          (format stream "~&| ~A | ~D | ~,3F | ~,3F | ~,2F | ~D, ~D | ~D, ~D | ~D, ~D |~%"
                  (second scene) (getf m :bodies) (getf m :general) (getf m :specialised)
                  (/ (getf m :specialised) (getf m :general))
                  (getf m :general-consed) (getf m :specialised-consed)
                  body-bytes body-bytes
                  (contact-bytes (getf m :general-block)) (contact-bytes (getf m :specialised-block))))
        (finish-output stream)))
    (format stream "~&(after the run: load ~A)~%" (load-average))))
;; What leaving features out saves:1 ends here

;; [[file:../physics.org::#FBNCH9][What leaving features out saves:2]]
(defun run-count-features (&key (stream *standard-output*) counter)
  "Print, as an Org table, the millions of instructions a step of each scene of +feature-scenes+
runs under the general step and under the step built for its features: a process of
tools/feature-one.lisp stepping the scene TO times less one stepping it FROM times, over TO -
FROM, counted by cachegrind (count-per-step). COUNTER, when given, is called as count-per-step
would be, in its place, and nothing is compiled first. #FBNCH9"
  (let ((root (namestring (asdf:system-source-directory "luv-physics")))
        (before (load-average)))
    ;; the engine compiled first, outside valgrind
    (unless counter (against-sample root '(:scalar) 0 0 0))
    (format stream "~&#+caption: feature scenes, millions of instructions a step over each scene's measured ~
                    steps (cachegrind: a process stepping to their end less one stepping to their start), ~
                    ~(~A~) family; ~A; load ~A~%"
            (car (last (available-kernel-families))) (cpu-model-name) before)
    (format stream "~&| scene | general | specialised | ratio | same state |~%")
    (format stream "~&|-------+---------+-------------+-------+------------|~%")
    (dolist (scene +feature-scenes+)
      (destructuring-bind (name what features from to) scene
        (declare (ignore features))
        (flet ((per-step (kind)
                 (funcall (or counter #'count-per-step) "feature" from to
                                 (lambda (steps) (list root (string-downcase name) kind (princ-to-string steps))))))
          (multiple-value-bind (general general-hash) (per-step "general")
            (multiple-value-bind (special special-hash) (per-step "specialised")
              (format stream "~&| ~A | ~,3F | ~,3F | ~,3F | ~:[no~;yes~] |~%"
                      what general special (/ special general) (= general-hash special-hash))
              (finish-output stream))))))
    (format stream "~&(after the run: load ~A)~%" (load-average))))
;; What leaving features out saves:2 ends here

;; [[file:../physics.org::#X7R3M5][Stiff and extreme cases:1]]
(defun pinch-between-sleepers (&key (seconds 2))
  "Let two balls of radius 0.25 m fall asleep on the basin floor 0.8 m apart, spawn a third
between them, overlapping each by 0.1 m, and run SECONDS. Return the largest normal impulse
of any contact over the ball's weight times the substep, and the fastest the ball moved. #X7R3M5"
  (let* ((world (make-physics-world :terrain (make-basin-terrain) :sleep t))
         (h (/ (physics-world-step-seconds world) (physics-world-substeps world)))
         (largest 0.0) (fastest 0.0))
    (add-physics-body world 3.6 0.25 4.0 :radius 0.25)
    (add-physics-body world 4.4 0.25 4.0 :radius 0.25)
    (loop repeat 120 until (= 2 (physics-world-sleeping-count world))
          do (step-physics-world world))
    (let ((ball (add-physics-body world 4.0 0.25 4.0 :radius 0.25 :mass 1.0)))
      (dotimes (i (* 60 seconds))
        (step-physics-world world)
        (let* ((contacts (physics-world-contacts world)) (geometry (contact-columns-geometry contacts)))
          (dotimes (k (contact-columns-length contacts))
            (setf largest (max largest (contact@ geometry k normal-impulse)))))
        (setf fastest (max fastest (speed-of world ball)))))
    (values (/ largest (* (abs (physics-world-gravity-y world)) h)) fastest)))

(defun pile-kinetic-energy (world balls)
  "The kinetic energy of BALLS in WORLD, in joules, translation and rotation, each a solid ball
of its own mass and radius. #X7R3M5"
  (let ((energy 0d0))
    (dolist (b balls energy)
      (multiple-value-bind (set row) (resolve-handle world b)
        (let ((buffer (set-buffer world set)))
          (with-body-columns (vx vy vz wx wy wz radius inverse-mass) buffer
            (let ((m (/ 1d0 (aref inverse-mass row))) (r (aref radius row)))
              (incf energy (* 0.5d0 m (+ (expt (aref vx row) 2) (expt (aref vy row) 2) (expt (aref vz row) 2)
                                         (* 0.4d0 r r (+ (expt (aref wx row) 2) (expt (aref wy row) 2)
                                                         (expt (aref wz row) 2)))))))))))))

(defun dead-pile (count &key (seconds 10) (rolling-resistance 0.0) (after 0) substeps-after)
  "Drop COUNT dead balls (radius 0.25 m, 1 kg, friction 0.6, restitution 0, ROLLING-RESISTANCE),
the scene :awake-basin unjittered, in the basin lattice with sleeping off and run SECONDS, then
AFTER seconds more, with SUBSTEPS-AFTER substeps a step when given. Return the kinetic energy at
each whole second, in joules; the fastest ball's speed at each whole second; and the speed of
the lowest point of the fastest ball at second SECONDS, which is zero when it rolls on the floor
without slipping. #X7R3M5"
  (let* ((world (make-scene-world :awake-basin :count count :kernels :auto
                                               :body-arguments (list :rolling-resistance rolling-resistance)))
         (balls (physics-world-handles world))
         (curve '()) (speeds '()) (slip nil))
    (loop for second from 1 to (+ seconds after)
          do (dotimes (i 60) (step-physics-world world))
             (let ((ball (reduce (lambda (a b) (if (>= (speed-of world a) (speed-of world b)) a b)) balls)))
               (push (pile-kinetic-energy world balls) curve)
               (push (speed-of world ball) speeds)
               (when (= second seconds)
                 (when substeps-after (setf (physics-world-substeps world) substeps-after))
                 (multiple-value-bind (vx vy vz) (physics-body-velocity world ball)
                   (multiple-value-bind (wx wy wz) (physics-body-angular-velocity world ball)
                     (declare (ignore wy))
                     ;; the lowest point moves at v + w x (0, -r, 0) = v + (r wz, 0, -r wx)
                     (setf slip (sqrt (+ (expt (+ vx (* 0.25 wz)) 2) (* vy vy)
                                         (expt (- vz (* 0.25 wx)) 2)))))))))
    (values (nreverse curve) (nreverse speeds) slip)))

(defun pile-at-rest-from (curve speeds)
  "The first whole second from which to the end of CURVE and SPEEDS (dead-pile's) the kinetic
energy stayed under 0.1 mJ and every ball under 1 mm/s, or NIL. #X7R3M5"
  (let ((from nil))
    (loop for second from 1 for e in curve for v in speeds
          do (if (and (< e 1d-4) (< v 0.001))
                 (unless from (setf from second))
                 (setf from nil)))
    from))

(defun thrown-into-pile (count &key (seconds 8) throw-at (shift 0.0) (seed nil))
  "The default scene at COUNT balls (each spawn point moved by up to 1 cm in x and z by the fixed
sequence of SEED, when given), its ball thrown at second THROW-AT (the scene's 4 s by default)
from a point SHIFT metres along x from the scene's, run SECONDS. Return the awake count at the end
of each second. #X7R3M5"
  (multiple-value-bind (world script) (make-scene-world :basin :count count :seed seed :shift shift
                                                               :throw-at throw-at)
    (loop for second below seconds
          do (dotimes (i 60)
               (funcall script (+ (* 60 second) i))
               (step-physics-world world))
          collect (physics-world-awake-count world))))

(defun column-contact-depths (count &key (radius 0.45) (seconds 10) (sleep t) (settle seconds))
  "Stack COUNT balls of RADIUS and 1 kg in the shaft of a world that lets bodies SLEEP or not, and
run SECONDS. Return each contact's overlap at the end, from the floor up, in slops, and as a second
value each contact's deepest overlap at the end of any step from second SETTLE on. #X7R3M5"
  (let* ((world (make-shaft-world :sleep sleep))
         (balls (loop for i below count
                      collect (add-physics-body world 0.5 (+ radius (* i 2.02 radius)) 0.5 :radius radius :mass 1.0)))
         (deepest (make-list count :initial-element 0.0)))
    (flet ((depths ()
             (let ((heights (mapcar (lambda (b) (nth-value 1 (physics-body-position world b))) balls)))
               (mapcar (lambda (overlap) (/ overlap *physics-linear-slop*))
                       (cons (- radius (first heights))
                             (loop for (a b) on heights while b collect (- (* 2 radius) (- b a))))))))
      (dotimes (i (* 60 seconds))
        (step-physics-world world)
        (when (>= (1+ i) (* 60 settle))
          (setf deepest (mapcar #'max deepest (depths)))))
      (values (depths) deepest))))

(defun soft-column-depths (count &key (mass 1.0))
  "The overlaps, from the floor up and in slops, at which a column of COUNT awake balls of MASS in
the shaft comes to rest by the soft contact's law ([[#G7Q3XR]]): each contact one slop plus its
load over its effective mass times omega squared. The floor's contact is stiffened by its load
and gives g over omega squared at twice the frequency; a contact between two balls, whose
effective mass is half a ball, gives the weight of the balls above it over half a ball times
omega squared. #X7R3M5"
  (let* ((world (make-shaft-world))
         (g (abs (physics-world-gravity-y world)))
         (h (/ (f32 (physics-world-step-seconds world)) (physics-world-substeps world)))
         (omega (* 2.0 (f32 pi) (min (f32 (physics-world-contact-hertz world)) (/ 0.25 h))))
         (slop (f32 (physics-world-slop world))))
    (cons (/ (+ slop (/ g (expt (* 2.0 omega) 2))) slop)
          (loop for above from (1- count) downto 1
                collect (/ (+ slop (/ (* above mass g) (* 0.5 mass omega omega))) slop)))))

(defun speed-of (world handle)
  "The speed of HANDLE's body. #X7R3M5"
  (multiple-value-bind (vx vy vz) (physics-body-velocity world handle)
    (sqrt (+ (* vx vx) (* vy vy) (* vz vz)))))

(defun fastest-and-parting (world bodies within)
  "The largest speed of BODIES in WORLD, and the largest speed at which two of them whose centres
lie closer than WITHIN (and apart) move away from each other along the line of their centres. #X7R3M5"
  (let ((fastest 0.0) (parting 0.0))
    (loop for (a . rest) on bodies
          do (setf fastest (max fastest (speed-of world a)))
             (multiple-value-bind (ax ay az) (physics-body-position world a)
               (multiple-value-bind (avx avy avz) (physics-body-velocity world a)
                 (dolist (b rest)
                   (multiple-value-bind (bx by bz) (physics-body-position world b)
                     (let ((d (sqrt (+ (expt (- bx ax) 2) (expt (- by ay) 2) (expt (- bz az) 2)))))
                       (when (< 1e-6 d within)
                         (multiple-value-bind (bvx bvy bvz) (physics-body-velocity world b)
                           (setf parting (max parting (/ (+ (* (- bx ax) (- bvx avx)) (* (- by ay) (- bvy avy))
                                                            (* (- bz az) (- bvz avz)))
                                                         d)))))))))))
    (values fastest parting)))

(defun make-shaft-world (&rest world-args)
  "A solid block with a one-cell shaft, x and z in [0,1), open from y = 0 upwards; WORLD-ARGS go
to make-physics-world. #X7R3M5"
  (let ((terrain (make-voxel-terrain)))
    (fill-terrain terrain -8 -1 -8 8 40 8 t)
    (fill-terrain terrain 0 0 0 1 40 1 nil)
    (apply #'make-physics-world :terrain terrain world-args)))

(defun stack-in-shaft (masses &key (radius 0.45) (seconds 10) (sleep t))
  "Stack balls of MASSES, bottom first, in the shaft of a world that lets bodies SLEEP or not;
run SECONDS; return the deepest penetration seen, the fastest speed seen, the top ball's drop
below its ideal height, and the deepest overlap between neighbours (or with the floor) at the
end. #X7R3M5"
  (let* ((world (make-shaft-world :sleep sleep))
         (balls (loop for m in masses for i from 0
                      collect (add-physics-body world 0.5 (+ radius (* i 2.02 radius)) 0.5
                                                :radius radius :mass m)))
         (deepest 0d0) (fastest 0.0))
    (dotimes (i (* 60 seconds))
      (step-physics-world world)
      (setf deepest (max deepest (physics-world-max-penetration world)))
      (dolist (b balls)
        (setf fastest (max fastest (speed-of world b)))))
    (let ((heights (mapcar (lambda (b) (nth-value 1 (physics-body-position world b))) balls)))
      (values deepest fastest
              (- (- (* (length masses) 2 radius) radius) (car (last heights)))
              (max (- radius (first heights))
                   (loop for (a b) on heights while b maximize (- (* 2 radius) (- b a))))))))

(defun heap-at-one-point (count &key (steps 300) (gravity '(0 -9.81 0)))
  "Spawn COUNT balls of radius 0.25 m at one point in the basin, 2 m above its floor, under
GRAVITY, and run STEPS steps; return the fastest speed seen, the fastest any pair overlapping by
more than the slop (where push-out acts) moved apart, and the deepest overlap left at the end.
#X7R3M5"
  (let* ((world (make-physics-world :terrain (make-basin-terrain) :gravity gravity))
         (balls (loop repeat count collect (add-physics-body world 4.0 2.0 4.0 :radius 0.25)))
         (fastest 0.0) (parting 0.0) (within (- 0.5 *physics-linear-slop*)))
    (dotimes (i steps)
      (step-physics-world world)
      (multiple-value-bind (f p) (fastest-and-parting world balls within)
        (setf fastest (max fastest f) parting (max parting p))))
    (values fastest parting (physics-world-max-penetration world))))

(defun heap-footprint (count &key (steps 60) (gravity '(0 0 0)) (every 10))
  "Spawn COUNT balls of radius 0.25 m at one point in the basin, 2 m above its floor, under
GRAVITY, and run STEPS steps. Return the bytes the world holds per body after a full
collection, the fastest ball's speed, the fastest any pair overlapping by more than the slop
moved apart at every EVERY-th step, the deepest overlap left at the end, and the processor
seconds a step took. #X7R3M5"
  (sb-ext:gc :full t)
  (let* ((before (sb-kernel:dynamic-usage))
         (world (make-physics-world :terrain (make-basin-terrain) :gravity gravity))
         (balls (loop repeat count collect (add-physics-body world 4.0 2.0 4.0 :radius 0.25)))
         (within (- 0.5d0 *physics-linear-slop*))
         (fastest 0d0) (parting 0d0) (cpu 0))
    (declare (type double-float fastest parting within) (type integer cpu))
    (let ((p (make-array (* 3 count) :element-type 'double-float))
          (v (make-array (* 3 count) :element-type 'double-float)))
    (dotimes (i steps)
      (let ((started (get-internal-run-time)))
        (step-physics-world world)
        (incf cpu (- (get-internal-run-time) started)))
      (loop for b in balls for k of-type index from 0 by 3
            do (multiple-value-bind (x y z) (physics-body-position world b)
                 (setf (aref p k) (float x 1d0) (aref p (+ k 1)) (float y 1d0) (aref p (+ k 2)) (float z 1d0)))
               (multiple-value-bind (x y z) (physics-body-velocity world b)
                 (setf (aref v k) (float x 1d0) (aref v (+ k 1)) (float y 1d0) (aref v (+ k 2)) (float z 1d0)
                       fastest (max fastest (sqrt (float (+ (* x x) (* y y) (* z z)) 1d0))))))
      (when (zerop (mod (1+ i) every))
        (loop for a of-type index from 0 below (* 3 count) by 3
              do (loop for b of-type index from (+ a 3) below (* 3 count) by 3
                       do (let* ((dx (- (aref p b) (aref p a))) (dy (- (aref p (+ b 1)) (aref p (+ a 1))))
                                 (dz (- (aref p (+ b 2)) (aref p (+ a 2))))
                                 (d (sqrt (+ (* dx dx) (* dy dy) (* dz dz)))))
                            (when (< 1d-6 d within)
                              (setf parting (max parting (/ (+ (* dx (- (aref v b) (aref v a)))
                                                               (* dy (- (aref v (+ b 1)) (aref v (+ a 1))))
                                                               (* dz (- (aref v (+ b 2)) (aref v (+ a 2)))))
                                                            d))))))))))
    (sb-ext:gc :full t)
    (values (round (- (sb-kernel:dynamic-usage) before) count) fastest parting
            (physics-world-max-penetration world) (/ cpu internal-time-units-per-second steps 1.0))))

(defun heap-table-plan (count)
  "The steps a heap of COUNT balls runs in the heap table, and every how many steps its parting
pairs are sampled (NIL: never): 120 and 10 below 20000 balls, 60 and 20 at 20000, 5 and never
above. #X7R3M5"
  (cond ((< count 20000) (values 120 10))
        ((= count 20000) (values 60 20))
        (t (values 5 nil))))

(defun run-heap-table (&key (sizes (list 1000 2000 5000 20000 *physics-body-budget*)))
  "Print an Org table of heaps spawned at one point without gravity (heap-footprint): for each
of SIZES the steps run (120; 60 at 20000 balls, sampling the pairs every 20th step; 5 above,
not sampling them, where the sampling alone would take hours), the bytes held per body, the
fastest ball, the fastest parting pair, the deepest overlap left, and the processor seconds a
step took. #X7R3M5"
  (format t "| bodies | steps | bytes a body | fastest ball m/s | fastest parting pair m/s | deepest left m | s a step |~%|-~%")
  (dolist (count sizes)
    (multiple-value-bind (steps every) (heap-table-plan count)
      (multiple-value-bind (bytes fastest parting deepest seconds)
          (heap-footprint count :steps steps :every (or every (1+ steps)))
        ;; an unsampled heap prints - and skips its parting figure
        (format t "| ~D | ~D | ~D | ~,2F | ~:[-~*~;~,2F~] | ~,3F | ~,3F |~%" count steps bytes fastest
                every parting deepest seconds)
        (finish-output))))
  (format t "~%load average at the end: ~A~%" (uiop:read-file-line "/proc/loadavg")))

(defun heaps-at-one-point (&key (sizes '(50 60 70 80 90 100 110 120 130 140 150)) (gravity '(0 -9.81 0)))
  "Run heap-at-one-point for each of SIZES under GRAVITY; return the fastest speed any heap saw,
the median and the largest over the heaps of their fastest parting pair, and the deepest overlap
any heap left. #X7R3M5"
  (let ((fastest 0.0) (partings '()) (deepest 0.0))
    (dolist (count sizes)
      (multiple-value-bind (speed parting pen) (heap-at-one-point count :gravity gravity)
        (setf fastest (max fastest speed) deepest (max deepest pen))
        (push parting partings)))
    (values fastest (median partings) (reduce #'max partings) deepest)))

(defun buried-ball (depth &key (seconds 3))
  "Spawn a ball of radius 0.25 m with its centre DEPTH metres down in a floor three cells thick,
over resident air, and run SECONDS. Return the fastest it moved between two steps (its
displacement over the step), its height at the end, and the height of a ball resting on the
floor. #X7R3M5"
  (let ((terrain (make-voxel-terrain)))
    (fill-terrain terrain -16 -16 -16 32 32 32 nil)
    (fill-terrain terrain -16 -3 -16 32 0 32 t)
    (let* ((world (make-physics-world :terrain terrain))
           (ball (add-physics-body world 0.5 (- depth) 0.5 :radius 0.25 :inside-cells :push-out))
           (dt (float (physics-world-step-seconds world) 1d0))
           (fastest 0d0))
      (multiple-value-bind (x0 y0 z0) (physics-body-position world ball)
        (dotimes (i (round seconds dt))
          (step-physics-world world)
          (multiple-value-bind (x y z) (physics-body-position world ball)
            (setf fastest (max fastest (/ (sqrt (+ (expt (- x x0) 2) (expt (- y y0) 2) (expt (- z z0) 2))) dt))
                  x0 x y0 y z0 z))))
      (values fastest (nth-value 1 (physics-body-position world ball)) (- 0.25 *physics-linear-slop*)))))

(define-physics-scene :mixed-masses
    "1000 balls of radius 0.25 m in the basin lattice, with sleeping off, their masses spread
evenly in log from 0.32 to 32 kg by the fixed sequence of the run's seed #X7R3M5"
  (:terrain () (make-basin-terrain))
  (:world :sleep nil :kernels :auto)
  (:bodies 1000 :spawn basin-spawn-point :radius 0.25 :masses (lambda (u) (expt 10.0 (- (* 2.0 u) 0.5))))
  (:seconds 15)
  (:features :terrain :body-contacts :friction))

(defun mixed-mass-pile (count &key (seconds 15) (brace-ratio *physics-brace-mass-ratio*) (seed 7))
  "Drop COUNT balls of the scene :mixed-masses, their masses drawn by the fixed sequence of SEED,
and run SECONDS with BRACE-RATIO. Return
the deepest overlap seen after the first two seconds, the last second in which a ball moved
faster than 0.1 m/s (0 if none after the first), the fastest speed in the last second, and
whether the world stayed finite and valid. #X7R3M5"
  (let* ((*physics-brace-mass-ratio* brace-ratio)
         (world (make-scene-world :mixed-masses :count count :seed seed))
         (balls (physics-world-handles world)) (deepest 0.0) (last-moving 0) (fastest-last 0.0))
    (dotimes (i (* 60 seconds))
      (step-physics-world world)
      (when (>= i 120) (setf deepest (max deepest (physics-world-max-penetration world))))
      (let ((fastest (reduce #'max balls :key (lambda (b) (speed-of world b)))))
        (when (and (>= i 60) (> fastest 0.1)) (setf last-moving (1+ (floor i 60))))
        (when (>= i (* 60 (1- seconds))) (setf fastest-last (max fastest-last fastest)))))
    (values deepest last-moving fastest-last (and (world-finite-p world) (validate-physics-world world)))))

(defun crowd-in-one-cell (count &key (radius 0.05) (side 1.0) (seconds 3) (kernels :auto))
  "Spawn COUNT balls of RADIUS (mass 0.01 kg) at fixed pseudo-random points of a cube of SIDE
metres in the basin, overlapping by the dozen, and run SECONDS. Return the contacts in the
overflow colour on the first step, the seconds until the overflow colour stays empty, the
fastest speed seen, the deepest overlap at the end, and whether every number stayed finite and
the world valid. #X7R3M5"
  (let* ((world (make-physics-world :terrain (make-basin-terrain) :kernels kernels))
         (sequence (fixed-sequence 12345)) (first-overflow nil) (cleared nil) (fastest 0.0)
         (balls (flet ((next () (* side (funcall sequence))))
                  (loop repeat count
                        collect (add-physics-body world (+ 4.0 (next) (* -0.5 side)) (+ 0.5 (next))
                                                  (+ 4.0 (next) (* -0.5 side)) :radius radius :mass 0.01)))))
    (dotimes (i (* 60 seconds))
      (step-physics-world world)
      (let ((overflow (physics-world-overflow-count world)))
        (unless first-overflow (setf first-overflow overflow))
        (cond ((plusp overflow) (setf cleared nil))
              ((null cleared) (setf cleared (/ (1+ i) 60.0)))))
      (dolist (b balls) (setf fastest (max fastest (speed-of world b)))))
    (values first-overflow cleared fastest (physics-world-max-penetration world)
            (and (world-finite-p world) (validate-physics-world world)))))

(defun world-finite-p (world)
  "Whether every position, velocity and angular velocity of WORLD's bodies is a finite number. #X7R3M5"
  (flet ((finite (column) (every (lambda (v) (<= (abs v) most-positive-single-float)) column)))
    (loop for buffer in (list (physics-world-awake world) (physics-world-sleeping world))
          always (with-body-columns (x y z vx vy vz wx wy wz) buffer
                   (let ((n (body-columns-length buffer)))
                     (every (lambda (column) (finite (subseq column 0 n))) (list x y z vx vy vz wx wy wz)))))))

(defun fountain-long-run (&key (minutes 10))
  "Run the fountain of the benchmarks (#B3NCH5) for MINUTES simulated minutes. Return the drops
alive at the end, whether every number stayed finite, the bytes consed per step after the first
minute, and the growth of the heap in bytes, after a full collection, from the end of the first
minute to the end. #X7R3M5"
  (multiple-value-bind (world script) (make-scene-world :fountain :kernels :scalar)
    (let ((finite t) (consed 0) (heap-1 0))
      (dotimes (i (* minutes 3600))
        (when (= i 3600)
          (sb-ext:gc :full t)
          (setf heap-1 (sb-kernel:dynamic-usage)))
        (let ((before (sb-ext:get-bytes-consed)))
          (funcall script i)
          (step-physics-world world)
          (when (>= i 3600) (incf consed (- (sb-ext:get-bytes-consed) before))))
        (when (zerop (mod i 600)) (setf finite (and finite (world-finite-p world)))))
      (sb-ext:gc :full t)
      (values (+ (physics-world-awake-count world) (physics-world-sleeping-count world))
              (and finite (world-finite-p world))
              (round consed (* (1- minutes) 3600))
              (- (sb-kernel:dynamic-usage) heap-1)))))

(defun throw-at-wall (speed start)
  "Throw a ball of radius 0.25 m at SPEED along x, without gravity, from x = START at a wall one
cell thick at x in [10,11); return where it is after 1.5 s. #X7R3M5"
  (let ((terrain (make-voxel-terrain)))
    (fill-terrain terrain -16 -1 -16 32 16 32 nil)
    (fill-terrain terrain 10 0 -16 11 16 32 t)
    (let* ((world (make-physics-world :terrain terrain :gravity '(0 0 0)))
           (ball (add-physics-body world start 2.0 0.5 :radius 0.25 :vx speed)))
      (dotimes (i 90) (step-physics-world world))
      (physics-body-position world ball))))

(defun rest-on-floor (&key (radius 0.25) (step-seconds 1/60) (x 0.5) (seconds 5))
  "Drop a ball of RADIUS from 2 m at X onto a floor, stepping STEP-SECONDS for SECONDS; return
its final height less its ideal resting height (radius less a slop), and whether it sleeps. #X7R3M5"
  (let ((terrain (make-voxel-terrain)) (x0 (floor x)))
    (fill-terrain terrain (- x0 16) -1 -16 (+ x0 16) 32 16 nil)
    (fill-terrain terrain (- x0 16) -1 -16 (+ x0 16) 0 16 t)
    (let* ((world (make-physics-world :terrain terrain :step-seconds step-seconds))
           (ball (add-physics-body world x 2.0 0.5 :radius radius)))
      (dotimes (i (round seconds step-seconds)) (step-physics-world world))
      (values (- (nth-value 1 (physics-body-position world ball)) (- radius *physics-linear-slop*))
              (not (physics-body-awake-p world ball))))))

(defun make-plain-floor-world (&key (sleep t) (gravity '(0 -9.81 0)))
  "A world that lets bodies SLEEP or not, under GRAVITY, over a floor of cells one thick, y in
[-1,0), below resident air: the cells [-16,32) on each axis. #X7R3M5"
  (let ((terrain (make-voxel-terrain)))
    (fill-terrain terrain -16 -16 -16 32 32 32 nil)
    (fill-terrain terrain -16 -1 -16 32 0 32 t)
    (make-physics-world :terrain terrain :sleep sleep :gravity gravity)))

(defun box-yaw (world handle)
  "How far HANDLE's body is turned about the vertical, in degrees, read from its orientation as
twice the angle of its quaternion's y part against its w part. #X7R3M5"
  (multiple-value-bind (qw qx qy) (physics-body-orientation world handle)
    (declare (ignore qx))
    (* 2 (/ 180 pi) (atan (abs qy) (abs qw)))))

(defun box-stack (densities &key (friction 0.6) (seconds 10) (sleep t))
  "Stack unit cubes of DENSITIES, bottom first, on the floor, all of FRICTION, each at its ideal
height (the k-th from the floor, from 0, at k + 0.5 m less k + 1 slops), in a world that lets
bodies SLEEP or not, and run SECONDS. Return the list of the cubes' depths below their ideal
heights at the end, in slops, bottom first; the farthest any centre moved across the floor at the
end of any step, in metres; the largest turn of any about the vertical at the end, in degrees;
and whether all sleep at the end. #X7R3M5"
  (let* ((world (make-plain-floor-world :sleep sleep))
         (slop *physics-linear-slop*)
         (ideal (loop for k from 0 below (length densities) collect (- (+ k 0.5) (* (1+ k) slop))))
         (cubes (loop for density in densities for y in ideal
                      collect (add-physics-box world 2.5 y 2.5 0.5 0.5 0.5 :density density :friction friction)))
         (drift 0.0))
    (dotimes (i (round (* 60 seconds)))
      (step-physics-world world)
      (dolist (b cubes)
        (multiple-value-bind (x y z) (physics-body-position world b)
          (declare (ignore y))
          (setf drift (max drift (sqrt (+ (expt (- x 2.5) 2) (expt (- z 2.5) 2))))))))
    (values (loop for b in cubes for y in ideal
                  collect (/ (- y (nth-value 1 (physics-body-position world b))) slop))
            drift (reduce #'max cubes :key (lambda (b) (box-yaw world b)))
            (notany (lambda (b) (physics-body-awake-p world b)) cubes))))

(defun plank-on-end (degrees &key (seconds 5) (sleep t))
  "Stand a plank of half-extents 0.1, 1 and 0.1 m (ten times as long as it is thick) on its end
on the floor, tipped by DEGREES about z, its lower edge a slop into the floor, in a world that
lets bodies SLEEP or not, and run SECONDS. Return the tilt of its long axis from the vertical at
the end, in degrees; how far its centre moved across the floor, in metres; whether it sleeps; and
the largest tilt at the end of any step. #X7R3M5"
  (let* ((world (make-plain-floor-world :sleep sleep))
         (a (* degrees (/ pi 180)))
         ;; turned by A about z, the plank's lowest edge is its corner at (-0.1, -1) in its frame
         (y (- (+ (cos a) (* 0.1 (sin a))) *physics-linear-slop*))
         (plank (add-physics-box world 2.5 y 2.5 0.1 1.0 0.1 :orientation (list (cos (/ a 2)) 0 0 (sin (/ a 2)))))
         (largest 0.0))
    (flet ((tilt ()
             ;; the long axis's upward part is the rotation matrix's middle entry, 1 - 2 (qx^2 + qz^2)
             (multiple-value-bind (qw qx qy qz) (physics-body-orientation world plank)
               (declare (ignore qw qy))
               (* (/ 180 pi) (acos (max -1.0 (min 1.0 (- 1 (* 2 (+ (* qx qx) (* qz qz)))))))))))
      (dotimes (i (round (* 60 seconds)))
        (step-physics-world world)
        (setf largest (max largest (tilt))))
      (multiple-value-bind (x y z) (physics-body-position world plank)
        (declare (ignore y))
        (values (tilt) (sqrt (+ (expt (- x 2.5) 2) (expt (- z 2.5) 2)))
                (not (physics-body-awake-p world plank)) largest)))))

(defun plank-balance-angle (&key (low 5.0) (high 6.5) (halvings 6))
  "Bisect the tilt at which the plank of plank-on-end, sleeping off, stops rocking back and
topples (its tilt after 5 s above 45 degrees), from LOW (which must rock back) and HIGH (which
must topple) by HALVINGS halvings; return the last tilt that rocked back and the first that
toppled, in degrees. #X7R3M5"
  (dotimes (i halvings (values low high))
    (let ((mid (* 0.5 (+ low high))))
      (if (> (plank-on-end mid :sleep nil) 45.0) (setf high mid) (setf low mid)))))

(defun packed-boxes (&key (gravity '(0 -9.81 0)) (seconds 10) (spacing 0.8) (bottom 1.0))
  "Pack 27 unit cubes in three layers of three by three, their centres SPACING apart (at 0.8 m
each overlaps its face neighbours by 0.2 m), the lowest layer's centres BOTTOM metres over the
floor, under GRAVITY, and run SECONDS. Return the fastest any cube moved; the fastest any two
cubes whose centres lay nearer than a side less a slop (still overlapping, for cubes that have
barely turned) moved apart; how many cubes end with a corner or the centre in the cells
(box-in-cells-p); how many are awake at the end; and whether the world stayed finite and valid.
#X7R3M5"
  (let* ((world (make-plain-floor-world :gravity gravity))
         (boxes (loop for i below 27
                      collect (add-physics-box world (+ 2.5 (* spacing (- (mod i 3) 1))) (+ bottom (* spacing (floor i 9)))
                                               (+ 2.5 (* spacing (- (mod (floor i 3) 3) 1))) 0.5 0.5 0.5)))
         (fastest 0.0) (parting 0.0) (within (- 1.0 *physics-linear-slop*)))
    (dotimes (i (round (* 60 seconds)))
      (step-physics-world world)
      (multiple-value-bind (f p) (fastest-and-parting world boxes within)
        (setf fastest (max fastest f) parting (max parting p))))
    (values fastest parting
            (count-if (lambda (b)
                        (multiple-value-bind (x y z) (physics-body-position world b)
                          (multiple-value-bind (qw qx qy qz) (physics-body-orientation world b)
                            (box-in-cells-p world x y z 0.5 0.5 0.5 qw qx qy qz))))
                      boxes)
            (physics-world-awake-count world)
            (and (world-finite-p world) (validate-physics-world world)))))

(defun box-stability-rows (row)
  "Call ROW, run-stability-table's (case held format argument...), for each box scene of the stiff
and extreme cases ([[#BXBRAC]]): a cube of density 100 on one of density 1, with friction and
without; the 10:1 plank on its end, and tipped either side of its balance angle; 27 cubes packed
overlapping, without gravity and falling onto the floor. #X7R3M5"
  (dolist (friction '(0.6 0.0))
    (multiple-value-bind (depths drift yaw asleep) (box-stack '(1 100) :friction friction)
      (funcall row (format nil "cube of density 100 set on a cube of density 1, friction ~,1F" friction)
               (and (every (lambda (d) (< (abs d) 0.5)) depths) (< drift 0.01) (< yaw 0.5) asleep)
               "after 10 s the lower ~,3F and the upper ~,3F slops below their heights; drift ~,4F m at ~
                most, turned ~,2F degrees; ~:[awake~;asleep~]" (first depths) (second depths) drift yaw asleep)))
  (multiple-value-bind (tilt drift asleep) (plank-on-end 0.0)
    (funcall row "plank of half-extents 0.1, 1, 0.1 m standing on its end" (and (< tilt 0.5) (< drift 0.01) asleep)
             "after 5 s tilted ~,3F degrees, moved ~,4F m; ~:[awake~;asleep~]" tilt drift asleep))
  (let ((balance (* (/ 180 pi) (atan 0.1))))
    (multiple-value-bind (low high) (plank-balance-angle)
      (funcall row "that plank tipped about an edge of its foot, sleeping off"
               (< (- balance 0.1) low balance high (+ balance 0.1))
               "rocks back from ~,3F degrees, topples from ~,3F (bisection, 6 halvings); atan(0.1) = ~,3F"
               low high balance)))
  (let ((push-max *physics-contact-push-max*))
    (multiple-value-bind (fastest parting) (packed-boxes :gravity '(0 0 0) :seconds 2 :bottom 3.0)
      (funcall row "27 unit cubes packed 0.2 m into each other, no gravity"
               (and (<= parting (* 1.25 push-max)) (< fastest (* (sqrt 3) push-max)))
               "over 2 s the fastest cube ~,3F m/s, the fastest parting pair ~,3F m/s" fastest parting))
    (multiple-value-bind (fastest parting inside awake ok) (packed-boxes)
      (funcall row "27 unit cubes packed 0.2 m into each other, falling onto the floor"
               (and (zerop inside) (zerop awake) ok)
               "fastest cube ~,3F m/s, fastest parting pair ~,3F m/s; after 10 s ~D in the cells, ~D awake; ~
                ~:[not finite or invalid~;finite and valid~]" fastest parting inside awake ok))))

(defun run-stability-table (&key (stream *standard-output*) (full t) (crowd (and full 10000)))
  "Print, as an Org table, what each stiff or extreme scene measured and whether it held; with
FULL false, only the rows whose scenes hold a few balls (not the piles, heaps and the fountain's
ten minutes). CROWD, when not NIL, is how many balls the crowd in one cell holds (10000 in the
full table, none in the short one). #X7R3M5"
  (format stream "~&#+caption: stiff and extreme cases; ~A; load ~A~%" (cpu-model-name) (load-average))
  (format stream "~&| case | measured | held |~%|------+----------+------|~%")
  (flet ((row (case held fmt &rest args)
           (format stream "~&| ~A | ~? | ~:[no~;yes~] |~%" case fmt args held)
           (finish-output stream)))
    (multiple-value-bind (pen speed drop left) (stack-in-shaft '(1.0 1000.0))
      (row "1000 kg ball landing on a 1 kg ball" (< pen 0.02)
           "deepest ~,4F m, fastest ~,3F m/s" pen speed)
      (row "1000 kg ball resting on a 1 kg ball" (and (< (abs (- left *physics-linear-slop*)) 0.001) (< pen 0.45))
           "after 10 s top ~,4F m low, deepest overlap ~,4F m; never through" drop left))
    ;; awake, the light ball never turns static for the heavy one: their contact keeps its give
    (multiple-value-bind (pen speed drop left) (stack-in-shaft '(1.0 1000.0) :sleep nil)
      (declare (ignore speed))
      (row "1000 kg ball resting on a 1 kg ball, sleeping off" (< (abs (- left *physics-linear-slop*)) 0.001)
           "after 10 s top ~,4F m low, deepest overlap ~,4F m (deepest seen ~,4F m)" drop left pen))
    (multiple-value-bind (pen speed drop left) (stack-in-shaft '(1000.0 1.0))
      (row "1 kg ball on a 1000 kg ball" (< pen 0.02)
           "deepest ~,4F m, fastest ~,3F m/s; after 10 s top ~,4F m low, overlap ~,4F m" pen speed drop left))
    ;; boxes: a heavy cube on a light one, a plank on its end, cubes packed into each other
    (box-stability-rows #'row)
    ;; bracing in a pile of many masses, and the same pile without it, each from twelve starts:
    ;; the deepest overlap of one start is the deepest of one moment, which one heavy landing sets
    (when full
      (dolist (ratio (list *physics-brace-mass-ratio* 1e9))
        (let ((runs (loop for seed in '(7 11 13 17 19 23 29 31 37 41 43 47)
                          collect (multiple-value-list (mixed-mass-pile 1000 :brace-ratio ratio :seed seed)))))
          (flet ((all (key) (mapcar key runs)))
            (let ((deepest (all #'first)) (last (reduce #'max (all #'second)))
                  (fastest (reduce #'max (all #'third))) (ok (every #'identity (all #'fourth))))
              (row (format nil "1000 balls of 0.32 to 32 kg, sleeping off, ~:[without bracing~;bracing~], twelve starts"
                           (< ratio 1e6))
                   (and ok (< (median deepest) 0.06) (< fastest 0.05))
                   "deepest overlap after 2 s ~,4F m in the median start, ~,4F m in the worst; a ball ~
                    faster than 0.1 m/s until second ~D; fastest in the last second ~,3F m/s; ~
                    ~:[not finite or invalid~;finite and valid~]"
                   (median deepest) (reduce #'max deepest) last fastest ok))))))
    (multiple-value-bind (pen speed drop left) (stack-in-shaft (make-list 20 :initial-element 1.0))
      (row "column of 20 balls" (< pen 0.05)
           "deepest ~,4F m, fastest ~,3F m/s; after 10 s top ~,4F m low, overlap ~,4F m" pen speed drop left))
    (let ((depths (column-contact-depths 20)))
      (row "column of 20 balls, each contact against its design depth (one slop)"
           (every (lambda (d) (<= d 1.1)) depths)
           "after 10 s, from the floor up, in slops: ~{~,2F~^ ~}" depths))
    ;; awake, against the same depth; the soft contact's law is what it would give unbraced
    (let ((depths (column-contact-depths 20 :sleep nil)) (law (soft-column-depths 20)))
      (row "column of 20 balls, sleeping off, each contact against its design depth (one slop)"
           (every (lambda (d) (<= d 1.1)) depths)
           "after 10 s, from the floor up, in slops: ~{~,2F~^ ~}; the soft contact's law gives ~
            ~,2F .. ~,2F" depths (second law) (car (last law))))
    (when full
      (let ((runs (append (loop for shift in '(0.0 0.001 0.002 0.003)
                                collect (thrown-into-pile 1000 :seconds 12 :throw-at 4 :shift shift))
                          (loop for seed from 1 to 24
                                collect (thrown-into-pile 1000 :seconds 12 :throw-at 4 :seed seed)))))
        (let ((at-8 (reduce #'max runs :key (lambda (r) (nth 7 r))))
              (at-12 (reduce #'max runs :key (lambda (r) (nth 11 r)))))
          (row "default scene, ball thrown at 4 s, 28 runs (throw 0-3 mm aside, 24 jittered spawns)"
               (and (<= at-8 10) (zerop at-12))
               "awake of 1001 in the worst run: ~D at 8 s, ~D at 12 s" at-8 at-12))))
    (when full
      (dolist (rho '(0.0 0.01))
        ;; the target is at 10 s; the run goes on to 45 s to tell when the pile comes to rest
        (multiple-value-bind (curve speeds slip)
            (dead-pile 500 :seconds 10 :after 35 :rolling-resistance rho)
          (row (format nil "500 dead balls, sleeping off~:[~;, rolling resistance ~:*~,2F~]" (and (> rho 0) rho))
               (and (< (nth 9 curve) 1e-4) (< (nth 9 speeds) 0.001))
               "kinetic energy at 1 .. 10 s, mJ: ~{~,3F~^ ~}; fastest at 10 s ~,4F m/s, its lowest point ~
                at ~,5F m/s; under 0.1 mJ and 1 mm/s from second ~:[(none)~;~:*~D~] of a 45 s run"
               (mapcar (lambda (e) (* 1000 e)) (subseq curve 0 10)) (nth 9 speeds) slip
               (pile-at-rest-from curve speeds))
          ;; a pile that meets the target at 10 s must stay at rest; the same run with four times
          ;; the substeps from the tenth second on tells the solver's part from the pile's
          (when (> rho 0)
            (flet ((after-10 (curve speeds)
                     (let ((most (reduce #'max (subseq curve 10))))
                       (list (* 1000 most) (+ 11 (position most (subseq curve 10)))
                             (* 1000 (reduce #'max (subseq speeds 10)))))))
              (multiple-value-bind (curve-16 speeds-16) (dead-pile 500 :seconds 10 :after 35 :rolling-resistance rho
                                                                       :substeps-after 16)
                (let ((four (after-10 curve speeds)) (sixteen (after-10 curve-16 speeds-16)))
                  (row (format nil "500 dead balls, sleeping off, rolling resistance ~,2F, staying at rest from 10 to 45 s" rho)
                       (and (< (first four) 0.1) (< (third four) 1.0))
                       "after 10 s the most kinetic energy ~,4F mJ at second ~D, the fastest ball ~,3F mm/s; ~
                        run on from the same state at 10 s with 16 substeps, ~,6F mJ at most (second ~D), ~
                        the fastest ~,3F mm/s" (first four) (second four) (third four)
                       (first sixteen) (second sixteen) (third sixteen)))))))))
    (when full
      (multiple-value-bind (speed median worst pen) (heaps-at-one-point)
        (row "heaps of 50 to 150 balls spawned at one point" (and (< speed 10.0) (< pen 0.01))
             "fastest ball ~,3F m/s; fastest parting pair ~,3F m/s in the median heap, ~,3F m/s in the worst; ~
              deepest left ~,4F m" speed median worst pen)))
    ;; without gravity nothing falls, so every speed in the heap is push-out
    (when full
      (multiple-value-bind (speed median worst pen) (heaps-at-one-point :gravity '(0 0 0))
        (row "heaps of 50 to 150 balls spawned at one point, no gravity" (and (< speed 10.0) (< pen 0.01))
             "fastest ball ~,3F m/s; fastest parting pair ~,3F m/s in the median heap, ~,3F m/s in the worst; ~
              deepest left ~,4F m" speed median worst pen)))
    (multiple-value-bind (load speed) (pinch-between-sleepers)
      (row "ball spawned pinched between two sleeping balls"
           (and (< load 50.0) (<= speed (+ *physics-contact-push-max* 0.01)))
           "largest impulse ~D times the ball's weight over a substep; fastest ~,3F m/s" (round load) speed))
    (dolist (depth '(0.2 0.5))
      (multiple-value-bind (speed y rest) (buried-ball depth)
        (row (format nil "ball spawned ~,1F m deep in the floor" depth)
             (and (<= speed (+ *physics-contact-push-max* 0.01)) (< (abs (- y rest)) 0.002))
             "left at ~,3F m/s at most; ends ~,4F m from its resting height" speed (- y rest))))
    (when crowd
      (multiple-value-bind (overflow cleared speed pen ok) (crowd-in-one-cell crowd)
        (row (format nil "~D balls of 0.05 m in one 1 m cell" crowd) (and ok cleared (< pen 0.02))
             "~D contacts in the overflow colour at first, none from ~:[never~;~:*~,2F s~]; fastest ~,3F m/s; ~
              deepest left ~,4F m; ~:[not finite or invalid~;finite and valid~]" overflow cleared speed pen ok)))
    (dolist (v '(20 50 100 200))
      (let ((ends (loop for k below 10 collect (throw-at-wall v (* k 0.137)))))
        (row (format nil "ball at ~D m/s at a one-cell wall" v) (every (lambda (x) (< x 10)) ends)
             "~D of 10 starts held" (count-if (lambda (x) (< x 10)) ends))))
    (dolist (r (list 0.01 (- *physics-reach-limit* *physics-speculative-margin*)))
      (multiple-value-bind (err asleep) (rest-on-floor :radius r)
        (row (format nil "radius ~,2F m at rest" r) (and asleep (< (abs err) 0.002))
             "height error ~,5F m, ~:[awake~;asleep~]" err asleep)))
    (dolist (dt '(1/10 1/2000))
      (multiple-value-bind (err asleep) (rest-on-floor :step-seconds dt)
        (row (format nil "step of ~A s" dt) (and asleep (< (abs err) 0.002))
             "height error ~,5F m, ~:[awake~;asleep~]" err asleep)))
    (dolist (x '(1e4 6e4))
      (multiple-value-bind (err asleep) (rest-on-floor :x x)
        (row (format nil "at x = ~D m" (round x)) (and asleep (< (abs err) 0.002))
             "height error ~,5F m, ~:[awake~;asleep~]" err asleep)))
    (let ((refused (handler-case (progn (rest-on-floor :x 1e5) nil)
                     (invalid-physics-parameter () t))))
      (row "at x = 100000 m" refused "~:[accepted~;refused with invalid-physics-parameter: the limit is ~D m~]"
           refused +physics-coordinate-limit+))
    ;; bodies squeezed between a moving box and cells ([[#SQU33Z]])
    (loop for (scene what) in '((:step "walker pressing 10 balls into a one-block step it climbs")
                                (:marbles "walker pressing 10 marbles into a one-block step it climbs")
                                (:wall "walker pressing 10 balls into a wall three blocks high")
                                (:press "box pressed down at 1 m/s onto 10 balls on the floor"))
          do (multiple-value-bind (outside lowest px py hash fastest cells box inside) (squeeze-scene :scalar scene)
               (declare (ignore lowest px py hash))
               (row what (and (zerop outside) (<= fastest 10.0))
                    "~D of 2400 positions outside the air; fastest ~,2F m/s; deepest into the cells ~,4F m, ~
                     into the box ~,4F m~:[~; (a centre inside the box)~]" outside fastest cells box inside)))
    ;; joints at the extremes ([[#J0XTRM]])
    (when full (joint-stability-rows #'row))
    (when full
      (multiple-value-bind (alive finite consed growth) (fountain-long-run)
        (row "fountain, 10 simulated minutes" (and finite (zerop consed) (< growth 1000000))
             "~D drops alive at the end; ~:[a number went non-finite~;all finite~]; ~D bytes consed per step ~
              after the first minute; heap ~@D bytes from minute 1 to 10" alive finite consed growth)))))
;; Stiff and extreme cases:1 ends here

;; [[file:../physics.org::#W9PREC][Error against run time:1]]
(defun open-air-world (&key floor (gravity '(0 -9.81 0)) (step-seconds 1/60) (substeps 4) (kernels :scalar))
  "A world over resident air in the cells [-16,32)^3 with, when FLOOR, a floor one cell thick at
y in [-1,0): a ball of radius R at rest on it has its centre at R less a slop. #W9PREC"
  (let ((terrain (make-voxel-terrain)))
    (fill-terrain terrain -16 -16 -16 32 32 32 nil)
    (when floor (fill-terrain terrain -16 -1 -16 32 0 32 t))
    (make-physics-world :terrain terrain :gravity gravity :step-seconds step-seconds
                        :substeps substeps :kernels kernels)))

(defvar *driven-seconds* 0d0
  "Simulated seconds stepped by drive since the last reset. #W9PREC")

(defun drive (world seconds &optional observe)
  "Step WORLD through SECONDS of simulated time, calling OBSERVE with the simulated time after
each step; return the wall-clock seconds the steps themselves took. #W9PREC"
  (let ((dt (float (physics-world-step-seconds world) 1d0)) (wall 0d0))
    (dotimes (i (round seconds dt) wall)
      (step-physics-world world)
      (incf wall (physics-world-last-step-real-seconds world))
      (incf *driven-seconds* dt)
      (when observe (funcall observe (* (1+ i) dt))))))

(defvar *accuracy-scenes* '()
  "The reference scenes of the sweep in the order defined, each (NAME FUNCTION MEASURE TOLERANCE). #W9PREC")

(defvar *own-accuracy-scenes* '()
  "The reference scenes of the sweep that only this engine runs, not the peers of [[#P33R5X]]
(the joints' of [[#J0PREC]]), each as an entry of *accuracy-scenes*. #W9PREC")

(defmacro define-accuracy-scene (name (measure tolerance &key (peers t)) doc &body body)
  "Define the reference scene NAME, as the function ACCURACY-SCENE-NAME, whose error is the
MEASURE (a string) and good enough under TOLERANCE: BODY runs with WORLD-ARGS bound to the setting's keywords for make-physics-world and
returns the error, the wall seconds its steps took, the world and a short note. With PEERS
false the scene goes to *own-accuracy-scenes*, which the peers do not run. #W9PREC"
  (let ((function (intern (format nil "ACCURACY-SCENE-~A" name)))
        (registry (if peers '*accuracy-scenes* '*own-accuracy-scenes*)))
    `(progn
       (defun ,function (world-args)
         ,doc
         (declare (ignorable world-args))
         ,@body)
       (setf ,registry
             (append (remove ',name ,registry :key #'first)
                     (list (list ',name ',function ,measure ,tolerance))))
       ',name)))
;; Error against run time:1 ends here

;; [[file:../physics.org::#W9PREC][Error against run time:2]]
(define-accuracy-scene free-fall ("largest height error, m" 0.01)
  "A ball falls from rest for 1 s in open air: the largest distance from y = -g t^2/2. #W9PREC"
  (let* ((world (apply #'open-air-world world-args))
         (ball (add-physics-body world 0.5 0.0 0.5))
         (worst 0d0)
         (wall (drive world 1.0 (lambda (time)
                                  (setf worst (max worst (abs (+ (nth-value 1 (physics-body-position world ball))
                                                                 (* 0.5d0 9.81d0 time time)))))))))
    (values worst wall world "")))

(define-accuracy-scene bounce ("largest relative apex error" 0.05)
  "A ball of restitution 0.8 dropped from 2 m onto the floor: its first three apex heights against
0.8^(2n) times 2 m. #W9PREC"
  (let* ((world (apply #'open-air-world :floor t world-args))
         (r 0.25) (ball (add-physics-body world 0.5 (+ 2.0 r) 0.5 :radius r :restitution 0.8))
         (apexes '()) (rising nil)
         (wall (drive world 4.0 (lambda (time)
                                  (declare (ignore time))
                                  (let ((vy (nth-value 1 (physics-body-velocity world ball))))
                                    (when (and rising (<= vy 0))
                                      (push (- (nth-value 1 (physics-body-position world ball)) r) apexes))
                                    (setf rising (> vy 0)))))))
    (setf apexes (reverse apexes))
    (values (if (< (length apexes) 3)
                1d0
                (loop for n from 1 to 3 for h in apexes
                      maximize (let ((ideal (* 2d0 (expt 0.8d0 (* 2 n))))) (/ (abs (- h ideal)) ideal))))
            wall world
            (format nil "apexes ~{~,3F~^ ~} m" (subseq apexes 0 (min 3 (length apexes)))))))

(define-accuracy-scene slide-to-roll ("largest speed error / v0" 0.01)
  "A ball launched sliding at 4 m/s, friction 0.4: speed v0 - mu g t until t = 2 v0/(7 mu g), then
5/7 v0; the largest speed error over 1 s, and when rolling began. #W9PREC"
  (let* ((world (apply #'open-air-world :floor t world-args))
         (r 0.25) (v0 4d0) (mu 0.4d0) (g 9.81d0)
         (ball (add-physics-body world 0.5 (- r *physics-linear-slop*) 0.5 :radius r :friction mu :vx v0))
         (t-roll (/ (* 2 v0) (* 7 mu g))) (began nil) (worst 0d0)
         (wall (drive world 1.0 (lambda (time)
                                  (multiple-value-bind (vx) (physics-body-velocity world ball)
                                    (let ((ideal (if (< time t-roll) (- v0 (* mu g time)) (* 5/7 v0)))
                                          (wz (nth-value 2 (physics-body-angular-velocity world ball))))
                                      (setf worst (max worst (/ (abs (- vx ideal)) v0)))
                                      (when (and (not began) (< (abs (+ vx (* wz r))) 0.01))
                                        (setf began time))))))))
    (values worst wall world
            (format nil "rolling from ~:[never~;~:*~,3F s~] (ideal ~,3F s)" began t-roll)
            began)))
;; Error against run time:2 ends here

;; [[file:../physics.org::#W9PREC][Error against run time:4]]
(define-accuracy-scene seams ("largest height error, m" 0.001)
  "A ball rolls across the floor's cell seams from 3 m/s for 3 s: the largest distance of its
centre from its resting height after the first 0.5 s, and its speed lost from 1 s to 3 s. #W9PREC"
  (let* ((world (apply #'open-air-world :floor t world-args))
         (r 0.25) (rest (- r *physics-linear-slop*))
         (ball (add-physics-body world 0.5 rest 0.5 :radius r :vx 3.0))
         (worst 0d0) (v1 nil) (v3 0d0)
         (wall (drive world 3.0 (lambda (time)
                                  (when (>= time 0.5)
                                    (setf worst (max worst (abs (- (nth-value 1 (physics-body-position world ball)) rest)))))
                                  (when (and (null v1) (>= time 1.0)) (setf v1 (speed-of world ball)))
                                  (setf v3 (speed-of world ball))))))
    (values worst wall world (format nil "speed lost 1-3 s: ~,3F %" (* 100 (/ (- v1 v3) v1))))))

(define-accuracy-scene resting ("largest |depth - slop|, m" 0.001)
  "A ball dropped 0.2 m onto the floor: over its third second, how far its depth strays from the
slop it should rest at. #W9PREC"
  (let* ((world (apply #'open-air-world :floor t world-args))
         (r 0.25) (ball (add-physics-body world 0.5 (+ r 0.2) 0.5 :radius r))
         (worst 0d0)
         (wall (drive world 3.0 (lambda (time)
                                  (when (>= time 2.0)
                                    (setf worst (max worst (abs (- (- r (nth-value 1 (physics-body-position world ball)))
                                                                   *physics-linear-slop*)))))))))
    (values worst wall world (format nil "~:[awake~;asleep~] at 3 s" (not (physics-body-awake-p world ball))))))
;; Error against run time:4 ends here

;; [[file:../physics.org::#W9PREC][Error against run time:5]]
(define-accuracy-scene head-on ("largest velocity error / approach speed" 0.01)
  "Balls of 1 kg and 2 kg meet head-on at 3 m/s each, restitution 0.5, without gravity: their
velocities after 1 s against momentum conservation and the restitution law (-3 and 0 m/s). #W9PREC"
  (let* ((world (apply #'open-air-world :gravity '(0 0 0) world-args))
         (a (add-physics-body world -1.0 0.5 0.5 :mass 1.0 :restitution 0.5 :vx 3.0))
         (b (add-physics-body world 1.0 0.5 0.5 :mass 2.0 :restitution 0.5 :vx -3.0))
         (wall (drive world 1.0))
         (va (physics-body-velocity world a)) (vb (physics-body-velocity world b)))
    (values (/ (max (abs (- va -3d0)) (abs vb)) 6d0) wall world
            (format nil "momentum ~,4F (ideal -3) kg m/s" (+ va (* 2 vb))))))

(define-accuracy-scene shaft-stack ("top's height error + drift, m" 0.01)
  "Six balls of radius 0.45 m stacked in a one-cell shaft for 10 s: how far the top ball ends from
its ideal height (every contact a slop deep) plus how far it drifted sideways. #W9PREC"
  (let* ((world (apply #'make-shaft-world world-args))
         (r 0.45) (s *physics-linear-slop*)
         (balls (loop for i below 6 collect (add-physics-body world 0.5 (+ r (* i 2.02 r)) 0.5 :radius r)))
         (wall (drive world 10.0)))
    (multiple-value-bind (x y z) (physics-body-position world (car (last balls)))
      (let ((drop (- (+ (- r s) (* 5 (- (* 2 r) s))) y))
            (drift (sqrt (+ (expt (- x 0.5) 2) (expt (- z 0.5) 2)))))
        (values (+ (abs drop) drift) wall world (format nil "top ~,4F m low, ~,4F m aside" drop drift))))))

(defun pile-energy (world balls)
  "The potential (above y = 0) plus kinetic energy of the 1 kg BALLS, J. #W9PREC"
  (loop for b in balls
        sum (+ (* 9.81d0 (nth-value 1 (physics-body-position world b))) (* 0.5d0 (expt (speed-of world b) 2)))))

(defun basin-pile (world-args)
  "The basin with 1000 balls dropped in, sleeping on, after 4 s: its energy, the deepest overlap
seen, the wall seconds and the world. #W9PREC"
  (let* ((world (apply #'make-basin-world 1000 :sleep t world-args))
         (balls (physics-world-handles world))
         (deepest 0d0)
         (wall (drive world 4.0 (lambda (time) (declare (ignore time))
                                  (setf deepest (max deepest (physics-world-max-penetration world)))))))
    (values (pile-energy world balls) deepest wall world)))

(defvar *converged-pile-energy* nil
  "The energy of the basin pile stepped at 240 Hz with 16 substeps, once computed. #W9PREC")

(define-accuracy-scene pile ("worst of |dE|/E and overlap / radius" 0.05)
  "The 1000-ball basin pile after 4 s: the worse of its energy's relative error against a
converged run (240 Hz, 16 substeps) and the deepest overlap seen as a fraction of the balls'
radius. #W9PREC"
  (let ((reference (or *converged-pile-energy*
                       (let ((*driven-seconds* 0d0))
                         (setf *converged-pile-energy* (basin-pile '(:step-seconds 1/240 :substeps 16)))))))
    (multiple-value-bind (energy deepest wall world) (basin-pile world-args)
      (let ((energy-error (/ (abs (- energy reference)) reference)))
        (values (max energy-error (/ deepest 0.25d0)) wall world
                (format nil "deepest ~,4F m; energy ~,1F J against ~,1F J (~,2,,,,,'eE)"
                        deepest energy reference energy-error))))))
;; Error against run time:5 ends here

;; [[file:../physics.org::#W9PREC][Error against run time:6]]
(defun rebound-heights (world-args restitution drop &key (rounds 4) (radius 0.25))
  "Drop a ball of RESTITUTION with its centre DROP metres above the contact level onto the
floor: its flights' apex heights above that level, the drop first, up to ROUNDS rebounds. Each
apex is the vertex of the parabola through a flight's first two positions a step apart. #W9PREC"
  (let* ((world (apply #'open-air-world :floor t world-args))
         (level (- radius *physics-linear-slop*))
         (ball (add-physics-body world 0.5 (+ level drop) 0.5 :radius radius :restitution restitution))
         (g 9.81d0) (dt (float (physics-world-step-seconds world) 1d0))
         (ys (list (float (nth-value 1 (physics-body-position world ball)) 1d0)))
         (apexes '()) (flying nil) (wall 0d0))
    (loop repeat (round 12 dt) while (and (<= (length apexes) rounds) (physics-body-awake-p world ball)) do
      (step-physics-world world)
      (incf wall (physics-world-last-step-real-seconds world))
      (incf *driven-seconds* dt)
      (push (float (nth-value 1 (physics-body-position world ball)) 1d0) ys)
      (when (cddr ys)
        (destructuring-bind (y2 y1 y0 &rest older) ys
          (declare (ignore older))
          ;; a step in free flight has the second difference -g dt^2
          (let ((free (< (abs (+ (- y0 (* 2 y1)) y2 (* g dt dt))) 1d-5)))
            (when (and free (not flying))
              (let ((b (+ (/ (- y1 y0) dt) (* 0.5d0 g dt))))
                (push (- (+ y0 (/ (* b (abs b)) (* 2 g))) level) apexes)))
            (setf flying free)))))
    (values (nreverse apexes) wall world)))

(defun rebound-errors (world-args restitution drop)
  "The relative errors against RESTITUTION squared of the ratios of successive apex heights
(rebound-heights) whose arrival speed exceeds the restitution threshold by a tenth; then the
wall seconds and the world. #W9PREC"
  (multiple-value-bind (heights wall world) (rebound-heights world-args restitution drop)
    (let ((e2 (* restitution restitution)) (limit (* 1.1d0 *physics-restitution-threshold*)))
      (values (loop for (before after) on heights while after
                    while (> (sqrt (* 2 9.81d0 before)) limit)
                    collect (/ (abs (- (/ after before) e2)) e2))
              wall world))))

(defparameter +bounce-restitutions+ '(0.2d0 0.3d0 0.4d0 0.5d0 0.6d0 0.7d0 0.8d0 0.9d0)
  "Restitutions of the bounce series. #W9PREC")

(defparameter +bounce-drops+ '(0.25d0 0.5d0 1d0 2d0 5d0)
  "Drop heights of the bounce series, m. #W9PREC")

(define-accuracy-scene bounce-series ("largest |rebound ratio - e^2| / e^2" 0.02)
  "Balls of every restitution of +bounce-restitutions+ dropped from every height of
+bounce-drops+: the worst relative error of a rebound ratio against e^2. #W9PREC"
  (let ((worst 0d0) (wall 0d0) (world nil) (count 0))
    (dolist (e +bounce-restitutions+)
      (dolist (drop +bounce-drops+)
        (multiple-value-bind (errors seconds last) (rebound-errors world-args e drop)
          (incf wall seconds) (setf world last) (incf count (length errors))
          (setf worst (reduce #'max errors :initial-value (if errors worst 1d0))))))
    (values worst wall world (format nil "~D rebounds" count))))

(defun struck-row (world-args &key (balls 5) (floor nil) (speed 2d0) (radius 0.25))
  "A row of BALLS touching balls of restitution 1 struck by its first: in free space, the first
moving at SPEED; on the FLOOR, the first rolled into the rest from 1.5 m away at SPEED (launched
sliding at 7/5 of it). Return the last ball's share of the row's momentum, the others' largest
speed over SPEED and the kinetic energy kept, at the step the last ball is fastest within 1 s,
then the wall seconds and the world. #W9PREC"
  (let* ((world (apply #'open-air-world :floor floor :gravity (if floor '(0 -9.81 0) '(0 0 0)) world-args))
         (y (if floor (- radius *physics-linear-slop*) 0.5))
         (row (loop for i from 1 below balls
                    collect (add-physics-body world (+ 2.0 (* i 2 radius)) y 0.5 :radius radius :restitution 1.0
                                                    :friction (if floor 0.6 0.0))))
         (first (add-physics-body world (if floor 0.5 2.0) y 0.5
                                  :radius radius :restitution 1.0 :friction (if floor 0.6 0.0)
                                  :vx (if floor (* 7/5 speed) speed)))
         (all (cons first row)) (best nil))
    (let ((wall (drive world 1.0 (lambda (time) (declare (ignore time))
                                   (let ((vs (mapcar (lambda (h) (float (physics-body-velocity world h) 1d0)) all)))
                                     (when (or (null best) (> (car (last vs)) (car (last best))))
                                       (setf best vs)))))))
      (let ((momentum (reduce #'+ best)))
        (values (/ (car (last best)) momentum)
                (/ (reduce #'max (mapcar #'abs (butlast best))) speed)
                (/ (reduce #'+ (mapcar (lambda (v) (* v v)) best)) (* speed speed))
                wall world)))))

(define-accuracy-scene cradle ("worst of momentum and energy not in the last ball" 0.1)
  "Five touching balls of restitution 1 in free space, the first struck at 2 m/s: the worse of
the momentum share and the kinetic energy the last ball does not carry. #W9PREC"
  (multiple-value-bind (share others kept wall world) (struck-row world-args)
    (values (max (- 1 share) (- 1 kept)) wall world
            (format nil "others ~,3F v0, energy ~,3F" others kept))))

(define-accuracy-scene struck-row ("worst of momentum and energy not in the last ball" 0.1)
  "A ball rolled at 3 m/s along the floor into a resting row of three, restitution 1: the worse
of the momentum share and the kinetic energy the last ball does not carry. #W9PREC"
  (multiple-value-bind (share others kept wall world) (struck-row world-args :balls 4 :floor t :speed 3d0)
    (values (max (- 1 share) (- 1 kept)) wall world
            (format nil "others ~,3F v0, energy ~,3F" others kept))))

(defun block-drop-ideal (speed dx dz radius restitution)
  "The analytic answer of a ball of RADIUS and RESTITUTION dropped at SPEED from 0.3 m above its
impact with the top edge (DZ 0) or the corner (DZ > 0) of the cell [0,1)^3, at the offsets DX, DZ
outside it: its centre's height at impact and at the start, the instant of impact, the
geometric normal there, the velocity coming in and the reflection law's velocity going out (the
last three as lists x y z). #W9PREC"
  (let* ((g 9.81d0) (r radius)
         (y-impact (+ 1d0 (sqrt (- (* r r) (* dx dx) (* dz dz)))))
         (y0 (+ y-impact 0.3d0))
         (u (sqrt (+ (* speed speed) (* 2 g (- y0 y-impact)))))
         (n (list (/ dx r) (/ (- y-impact 1d0) r) (/ dz r)))
         (v-in (list 0d0 (- u) 0d0))
         (vn (reduce #'+ (mapcar #'* v-in n))))
    (values y-impact y0 (/ (- u speed) g) n v-in
            (mapcar (lambda (v k) (- v (* (+ 1 restitution) vn k))) v-in n))))

(defun drop-onto-block (world-args &key (speed 5d0) (dx 0.1d0) dz (restitution 0.5d0) (radius 0.25d0) box)
  "Drop a frictionless ball of RESTITUTION straight down at SPEED onto the lone cell [0,1)^3 (with
BOX, a kinematic box at rest posted there every step instead): onto its top edge x = 1, y = 1 at
the offset DX outside it, or with DZ onto its corner x = z = 1.
Return the angles, degrees, of the impulse it took from the geometric normal at impact and of
its outgoing velocity from the reflection law's, then the wall seconds and the world. #W9PREC"
  (multiple-value-bind (y-impact y0 t-impact n v-in ideal)
      (block-drop-ideal speed dx (or dz 0d0) radius restitution)
    (declare (ignore y-impact))
  (let* ((world (apply #'open-air-world world-args))
         (g 9.81d0)
         (ball (progn (unless box (fill-terrain (physics-world-terrain world) 0 0 0 1 1 1 t))
                      (add-physics-body world (+ 1d0 dx) y0 (if dz (+ 1d0 dz) 0.5d0) :radius radius :friction 0.0
                                        :restitution restitution :vy (- speed))))
         (dt (float (physics-world-step-seconds world) 1d0))
         (time 0d0) (hit nil) (out nil) (wall 0d0))
    (loop repeat 120 until out do
      (when box (post-physics-box world 0.5d0 0.5d0 0.5d0 0.5d0 0.5d0 0.5d0 :owner :block))
      (step-physics-world world)
      (incf wall (physics-world-last-step-real-seconds world))
      (incf *driven-seconds* dt)
      (incf time dt)
      (multiple-value-bind (vx vy vz) (physics-body-velocity world ball)
        (cond ((and (not hit) (> (abs (- vy (- (- speed) (* g time)))) 1d-3)) (setf hit time))
              ;; a step after the impact, its velocity taken back to the instant of impact
              ((and hit (> time (+ hit dt)))
               (setf out (list vx (+ vy (* g (- time t-impact))) vz))))))
    (if out
        (values (angle-between (mapcar #'- out v-in) n) (angle-between out ideal) wall world)
        (values 180d0 180d0 wall world)))))

(defun block-drops (world-args corner &optional box)
  "drop-onto-block at 2, 5 and 10 m/s and offsets 0.05 to 0.2 m (0.7 of that on each axis at a
CORNER), onto the cell or with BOX onto a posted box: the largest impulse angle and outgoing
angle, the wall seconds and the last world. #W9PREC"
  (let ((impulse 0d0) (outgoing 0d0) (wall 0d0) (world nil))
    (dolist (speed '(2d0 5d0 10d0))
      (dolist (offset '(0.05d0 0.1d0 0.15d0 0.2d0))
        (multiple-value-bind (a b seconds last)
            (if corner
                (drop-onto-block world-args :speed speed :dx (* 0.7d0 offset) :dz (* 0.7d0 offset) :box box)
                (drop-onto-block world-args :speed speed :dx offset :box box))
          (setf impulse (max impulse a) outgoing (max outgoing b) world last)
          (incf wall seconds))))
    (values impulse outgoing wall world)))

(defun oblique-pair (world-args &key (speed 5d0) (offset 0.2d0) (restitution 0.5d0) (radius 0.25d0))
  "In free space a frictionless ball of RESTITUTION moving at SPEED along x strikes a resting
equal one whose centre lies OFFSET aside in y: the angles, degrees, of the struck ball's
velocity (the impulse's direction) from the line of centres at the touch, and of the striker's
velocity from the one the reflection law gives, then the wall seconds and the world. #W9PREC"
  (let* ((world (apply #'open-air-world :gravity '(0 0 0) world-args))
         (a (add-physics-body world 0.0d0 (+ 0.5d0 offset) 0.5d0 :radius radius :friction 0.0
                                        :restitution restitution :vx speed))
         (b (add-physics-body world 1.0d0 0.5d0 0.5d0 :radius radius :friction 0.0 :restitution restitution))
         (reach (* 2 radius))
         (n (list (/ (sqrt (- (* reach reach) (* offset offset))) reach) (/ (- offset) reach) 0d0))
         (vn (* speed (first n)))
         (ideal (list (- speed (* 0.5d0 (+ 1 restitution) vn (first n))) (- (* 0.5d0 (+ 1 restitution) vn (second n))) 0d0))
         (wall (drive world 0.5)))
    (flet ((angle (u v)
             (let ((c (/ (reduce #'+ (mapcar #'* u v))
                         (sqrt (* (reduce #'+ (mapcar #'* u u)) (reduce #'+ (mapcar #'* v v)))))))
               (* (/ 180 pi) (acos (max -1d0 (min 1d0 c)))))))
      (values (angle (multiple-value-list (physics-body-velocity world b)) n)
              (angle (multiple-value-list (physics-body-velocity world a)) ideal)
              wall world))))

(define-accuracy-scene oblique-pair ("largest impulse angle from the line of centres, degrees" 1)
  "oblique-pair at 2, 5 and 10 m/s and offsets of 0.1 to 0.4 m: the largest angle of the struck
ball's velocity from the line of centres at the touch. #W9PREC"
  (let ((impulse 0d0) (outgoing 0d0) (wall 0d0) (world nil))
    (dolist (speed '(2d0 5d0 10d0))
      (dolist (offset '(0.1d0 0.2d0 0.3d0 0.4d0))
        (multiple-value-bind (i o seconds last) (oblique-pair world-args :speed speed :offset offset)
          (setf impulse (max impulse i) outgoing (max outgoing o) world last)
          (incf wall seconds))))
    (values impulse wall world (format nil "striker off by up to ~,2F deg" outgoing))))

(define-accuracy-scene edge-drop ("largest impulse angle from the normal, degrees" 1)
  "A frictionless ball of restitution 0.5 dropped onto a block's top edge (block-drops): the
largest angle of its impulse from the geometric normal at impact. #W9PREC"
  (multiple-value-bind (impulse outgoing wall world) (block-drops world-args nil)
    (values impulse wall world (format nil "outgoing off by up to ~,2F deg" outgoing))))

(define-accuracy-scene corner-drop ("largest impulse angle from the normal, degrees" 1)
  "A frictionless ball of restitution 0.5 dropped onto a block's top corner (block-drops): the
largest angle of its impulse from the geometric normal at impact. #W9PREC"
  (multiple-value-bind (impulse outgoing wall world) (block-drops world-args t)
    (values impulse wall world (format nil "outgoing off by up to ~,2F deg" outgoing))))
;; Error against run time:6 ends here

;; [[file:../physics.org::#W9PREC][Error against run time:7]]
(define-accuracy-scene rolling-resistance ("largest speed error / v0" 0.01)
  "A ball of radius 0.25 m rolling without sliding at 2 m/s along the floor, rolling resistance
0.05: its speed against v0 - 5/7 rho g t over 2 s. #W9PREC"
  (let* ((world (apply #'open-air-world :floor t world-args))
         (r 0.25) (v0 2d0) (rho 0.05d0) (g 9.81d0)
         (ball (add-physics-body world 0.5 (- r *physics-linear-slop*) 0.5 :radius r :rolling-resistance rho :vx v0))
         (worst 0d0))
    (set-physics-body-angular-velocity world ball 0 0 (/ (- v0) r))
    (let ((wall (drive world 2.0 (lambda (time)
                                   (let ((vx (physics-body-velocity world ball)))
                                     (setf worst (max worst (/ (abs (- vx (max 0d0 (- v0 (* 5/7 rho g time))))) v0))))))))
      (values worst wall world
              (format nil "speed at the end ~,3F m/s (ideal ~,3F)" (physics-body-velocity world ball) (- v0 (* 5/7 rho g 2)))))))
;; Error against run time:7 ends here

;; [[file:../physics.org::#W9PREC][Error against run time:9]]
(defparameter +sweep-rates+ '(30 60 120 240)
  "Step rates of the sweep, Hz. #W9PREC")

(defparameter +sweep-substeps+ '(1 2 4 8)
  "Substep counts of the sweep. #W9PREC")

(defun run-accuracy-point (scene hz substeps family)
  "Run SCENE twice at HZ, SUBSTEPS and FAMILY; return its plist: :error, :ms (the faster run's
wall milliseconds per simulated second), :note, :hash, and :repeated (whether the second run
reached the same error and state hash). #W9PREC"
  (flet ((once ()
           (let ((*driven-seconds* 0d0))
             (multiple-value-bind (err wall world note)
                 (funcall (second (assoc scene *accuracy-scenes*)) (list :step-seconds (/ 1 hz) :substeps substeps :kernels family))
               (list :scene scene :hz hz :substeps substeps :family family :error (float err 1d0)
                     :ms (/ (* 1000 wall) *driven-seconds*) :note note
                     :hash (physics-world-state-hash world))))))
    (let ((a (once)) (b (once)))
      (list* :repeated (and (= (getf a :hash) (getf b :hash)) (= (getf a :error) (getf b :error)))
             :ms (min (getf a :ms) (getf b :ms))
             a))))

(defun run-accuracy-sweep (&key (scenes (mapcar #'first *accuracy-scenes*)) (rates +sweep-rates+)
                                (substeps +sweep-substeps+)
                                (families (available-kernel-families)))
  "Run every scene of SCENES at every step rate of RATES, substep count of SUBSTEPS and kernel
family of FAMILIES; return one plist per point, families innermost (see run-accuracy-point). #W9PREC"
  (loop for scene in scenes
        nconc (loop for hz in rates
                    nconc (loop for n in substeps
                                nconc (loop for family in families
                                            collect (run-accuracy-point scene hz n family))))))
;; Error against run time:9 ends here

;; [[file:../physics.org::#W9PREC][Error against run time:11]]
(defun point-label (p)
  "A setting as it is named in the tables: family, rate and substeps. #W9PREC"
  (format nil "~(~A~) ~D Hz x ~D" (getf p :family) (getf p :hz) (getf p :substeps)))

(defun pareto-front (points)
  "The points no other point beats on both run time and error, fastest first. #W9PREC"
  (let ((best most-positive-double-float) (front '()))
    (dolist (p (sort (copy-list points) #'< :key (lambda (p) (getf p :ms))) (nreverse front))
      (when (< (getf p :error) best)
        (setf best (getf p :error))
        (push p front)))))

(defun good-enough (points tolerance)
  "The cheapest of POINTS whose error is within TOLERANCE, or, when none is, the most accurate:
either way a point of the Pareto front. #W9PREC"
  (let ((within (remove-if-not (lambda (p) (<= (getf p :error) tolerance)) points)))
    (if within
        (reduce (lambda (a b) (if (<= (getf a :ms) (getf b :ms)) a b)) within)
        (reduce (lambda (a b) (if (or (< (getf a :error) (getf b :error))
                                      (and (= (getf a :error) (getf b :error)) (<= (getf a :ms) (getf b :ms))))
                                  a b))
                points))))
;; Error against run time:11 ends here

;; [[file:../physics.org::#W9PREC][Error against run time:12]]
(defun print-sweep-table (points stream)
  "Print POINTS as an Org table: a row per scene and setting, the error, the note, the run time
of each family, and whether every family reached the same state hash and error, twice. #W9PREC"
  (let ((families (remove-duplicates (mapcar (lambda (p) (getf p :family)) points) :from-end t)))
    (format stream "~&| scene | Hz | substeps | error | note |~{ ms/s ~(~A~) |~} same hash |~%" families)
    (format stream "~&|-------+----+----------+-------+------+~{~*------+~}-----------|~%" families)
    (loop for (p . rest) on points by (lambda (l) (nthcdr (length families) l))
          do (let ((group (cons p (subseq rest 0 (1- (length families))))))
               (format stream "~&| ~(~A~) | ~D | ~D | ~,3,,,,,'eE | ~A |~{ ~,2F |~} ~:[no~;yes~] |~%"
                       (getf p :scene) (getf p :hz) (getf p :substeps) (getf p :error) (getf p :note)
                       (mapcar (lambda (q) (getf q :ms)) group)
                       (every (lambda (q) (and (getf q :repeated) (= (getf q :hash) (getf p :hash))
                                               (= (getf q :error) (getf p :error))))
                              group))))))

(defun print-sweep-best (points stream)
  "Print, a line per scene, the cheapest setting within the scene's tolerance and the settings of
its Pareto front. #W9PREC"
  (loop for (scene nil measure tolerance) in *accuracy-scenes*
        for mine = (remove scene points :key (lambda (p) (getf p :scene)) :test-not #'eq)
        when mine
          do (let ((best (good-enough mine tolerance)))
               (format stream "~&- ~(~A~) (~A): ~:[nothing is within ~A; the most accurate is~;~
                               the cheapest within ~A is~] ~A, error ~,2,,,,,'eE at ~,2F ms/s.~
                               ~%  Pareto front:~{ ~A~^,~}.~%"
                       scene measure (<= (getf best :error) tolerance) tolerance (point-label best)
                       (getf best :error) (getf best :ms) (mapcar #'point-label (pareto-front mine))))))
;; Error against run time:12 ends here

;; [[file:../physics.org::#W9PREC][Error against run time:13]]
(defparameter +substep-colours+ '((1 . "#c0392b") (2 . "#d68910") (4 . "#1e8449") (8 . "#2471a3"))
  "The colour of each substep count's curves in the diagrams. #W9PREC")

(defparameter +family-dashes+ '((:scalar . "") (:sse . "7 3") (:avx2 . "2 2"))
  "The dash pattern of each kernel family's curves in the diagrams. #W9PREC")

(defun write-log-axes (out width height x0 y0 x1 y1 xmin xmax ymin ymax title measure)
  "Write to OUT the head of a WIDTH by HEIGHT SVG diagram and its axes: the plot's frame from X0 Y0
to X1 Y1, a grid line at each power of ten from XMIN to XMAX and YMIN to YMAX, the TITLE, the wall
time along x and MEASURE along y. The work-precision diagrams and the peers' share it. #W9PREC"
  (flet ((sx (v) (+ x0 (* (- x1 x0) (/ (- v xmin) (- xmax xmin)))))
         (sy (v) (- y1 (* (- y1 y0) (/ (- v ymin) (- ymax ymin))))))
    (format out "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"~D\" height=\"~D\" viewBox=\"0 0 ~D ~D\" font-family=\"sans-serif\" font-size=\"11\">~%" width height width height)
    (format out "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>~%")
    (format out "<text x=\"~D\" y=\"18\" font-size=\"13\">~A</text>~%" x0 title)
    (loop for k from xmin to xmax
          do (format out "<line x1=\"~,1F\" y1=\"~D\" x2=\"~,1F\" y2=\"~D\" stroke=\"#ddd\"/><text x=\"~,1F\" y=\"~D\" text-anchor=\"middle\">10<tspan dy=\"-5\" font-size=\"8\">~D</tspan></text>~%"
                     (sx k) y0 (sx k) y1 (sx k) (+ y1 16) k))
    (loop for k from ymin to ymax
          do (format out "<line x1=\"~D\" y1=\"~,1F\" x2=\"~D\" y2=\"~,1F\" stroke=\"#ddd\"/><text x=\"~D\" y=\"~,1F\" text-anchor=\"end\">10<tspan dy=\"-5\" font-size=\"8\">~D</tspan></text>~%"
                     x0 (sy k) x1 (sy k) (- x0 6) (+ (sy k) 4) k))
    (format out "<rect x=\"~D\" y=\"~D\" width=\"~D\" height=\"~D\" fill=\"none\" stroke=\"#444\"/>~%" x0 y0 (- x1 x0) (- y1 y0))
    (format out "<text x=\"~D\" y=\"~D\" text-anchor=\"middle\">wall ms per simulated second</text>~%" (round (+ x0 x1) 2) (+ y1 34))
    (format out "<text transform=\"translate(18 ~D) rotate(-90)\" text-anchor=\"middle\">~A</text>~%" (round (+ y0 y1) 2) measure)))

(defun write-work-precision-svg (path title measure points)
  "Write to PATH an SVG work-precision diagram of POINTS (one scene): log10 of the error against
log10 of the wall milliseconds per simulated second, one curve per family and substep count
through its step rates. Errors below 1e-9 are drawn at 1e-9. #W9PREC"
  (let* ((x0 72) (x1 500) (y0 34) (y1 384) (width 690) (height 440)
         (lx (lambda (p) (log (max 1d-3 (getf p :ms)) 10d0)))
         (ly (lambda (p) (log (max 1d-9 (getf p :error)) 10d0)))
         (xmin (floor (reduce #'min points :key lx))) (xmax (max (1+ xmin) (ceiling (reduce #'max points :key lx))))
         (ymin (floor (reduce #'min points :key ly))) (ymax (max (1+ ymin) (ceiling (reduce #'max points :key ly)))))
    (flet ((sx (v) (+ x0 (* (- x1 x0) (/ (- v xmin) (- xmax xmin)))))
           (sy (v) (- y1 (* (- y1 y0) (/ (- v ymin) (- ymax ymin))))))
      (with-open-file (out path :direction :output :if-exists :supersede)
        (write-log-axes out width height x0 y0 x1 y1 xmin xmax ymin ymax title measure)
        (let ((row 0))
          (dolist (family (remove-duplicates (mapcar (lambda (p) (getf p :family)) points) :from-end t))
            (dolist (n (remove-duplicates (mapcar (lambda (p) (getf p :substeps)) points) :from-end t))
              (let ((curve (sort (remove-if-not (lambda (p) (and (eq (getf p :family) family) (= (getf p :substeps) n)))
                                                points)
                                 #'< :key (lambda (p) (getf p :hz))))
                    (colour (or (cdr (assoc n +substep-colours+)) "#555"))
                    (dash (or (cdr (assoc family +family-dashes+)) "")))
                (format out "<polyline fill=\"none\" stroke=\"~A\" stroke-width=\"1.6\" stroke-dasharray=\"~A\" points=\"~{~,1F,~,1F~^ ~}\"/>~%"
                        colour dash (loop for p in curve collect (sx (funcall lx p)) collect (sy (funcall ly p))))
                (dolist (p curve)
                  (format out "<circle cx=\"~,1F\" cy=\"~,1F\" r=\"2.6\" fill=\"~A\"/>~%" (sx (funcall lx p)) (sy (funcall ly p)) colour))
                (let ((y (+ y0 8 (* 15 row))))
                  (format out "<line x1=\"~D\" y1=\"~D\" x2=\"~D\" y2=\"~D\" stroke=\"~A\" stroke-width=\"1.6\" stroke-dasharray=\"~A\"/><text x=\"~D\" y=\"~D\">~(~A~) x ~D substeps</text>~%"
                          (+ x1 14) y (+ x1 44) y colour dash (+ x1 50) (+ y 4) family n))
                (incf row)))))
        (format out "<text x=\"~D\" y=\"~D\" font-size=\"10\" fill=\"#555\">points: 30, 60, 120, 240 Hz</text>~%" (+ x1 14) (- y1 4))
        (format out "</svg>~%")))
    path))
;; Error against run time:13 ends here

;; [[file:../physics.org::#W9PREC][Error against run time:14]]
(defun run-accuracy-report (&key (directory "report/") (stream *standard-output*))
  "The sweep of every scene, those only this engine runs after the others, written as
report/work-precision.org (the table), report/work-precision-best.org (the Pareto-best setting
per scene) and one SVG diagram per scene, report/wp-SCENE.svg. Print the table to STREAM as
well. #W9PREC"
  (let* ((*accuracy-scenes* (append *accuracy-scenes* *own-accuracy-scenes*))
         (points (run-accuracy-sweep)))
    (with-open-file (out (merge-pathnames "work-precision.org" directory) :direction :output :if-exists :supersede)
      (format out "#+caption: error and wall ms per simulated second; ~A; load ~A~%" (cpu-model-name) (load-average))
      (print-sweep-table points out))
    (print-sweep-table points stream)
    (with-open-file (out (merge-pathnames "work-precision-best.org" directory) :direction :output :if-exists :supersede)
      (print-sweep-best points out))
    (print-sweep-best points stream)
    (dolist (entry *accuracy-scenes*)
      (write-work-precision-svg (merge-pathnames (format nil "wp-~(~A~).svg" (first entry)) directory)
                                (format nil "~(~A~): error against run time" (first entry)) (third entry)
                                (remove (first entry) points :key (lambda (p) (getf p :scene)) :test-not #'eq)))
    points))
;; Error against run time:14 ends here

;; [[file:../physics.org::#J0PREC][The pendulum and the spring:1]]
(define-accuracy-scene pendulum ("worst of period and energy a minute, relative" 0.02 :peers nil)
  "A 1 m pendulum released at 90 degrees, a minute: the worse of its period's error against the
elliptic period and its energy's drift over the minute, both relative. #J0PREC"
  (multiple-value-bind (period energy wall world) (pendulum-run 90 60 :world-args world-args)
    (let ((exact (elliptic-period 90 1)))
      (values (max (/ (abs (- period exact)) exact) (abs (- energy 1)))
              wall world
              (format nil "period ~,3@F %, energy ~,3@F % a minute"
                      (* 100 (/ (- period exact) exact)) (* 100 (- energy 1)))))))

(define-accuracy-scene spring ("worst of period and peak ratio, relative" 0.01 :peers nil)
  "A spring joint of 1 Hz and damping ratio 0.1 on a ball of 1 kg, ten seconds: the worse of its
period's error against the damped oscillator's and its first four peak ratios' against
exp(-zeta omega T), relative. #J0PREC"
  (multiple-value-bind (period ratios wall world) (spring-run 1.0 0.1 10 :world-args world-args)
    (multiple-value-bind (want decay) (damped-oscillator 1.0 0.1)
      (let ((ratio-error (if (>= (length ratios) 4)
                             (loop for r in ratios repeat 4 maximize (/ (abs (- r decay)) decay))
                             1d0)))
        (values (max (/ (abs (- period want)) want) ratio-error) wall world
                (format nil "period ~,3@F %, peak ratios off by up to ~,3F %"
                        (* 100 (/ (- period want) want)) (* 100 ratio-error)))))))
;; The pendulum and the spring:1 ends here

;; [[file:../physics.org::#BXPREC][A box on an incline and a box across the seams:1]]
(defun box-incline-run (world-args &key (slope 0.7) (mu 0.5))
  "A unit cube of friction MU set down at rest on the floor of open-air-world under gravity tilted
by atan SLOPE about z, stepped 1.5 s under WORLD-ARGS: its acceleration along the slope between
the last step before 0.5 s and the last step, the closed form g (sin theta - mu cos theta), and
the wall seconds and the world. #BXPREC"
  (let* ((theta (atan slope)) (g 9.81d0)
         (world (apply #'open-air-world :floor t :gravity (list (* g (sin theta)) (- (* g (cos theta))) 0)
                       world-args))
         (box (add-physics-box world -10.5 (- 0.5 *physics-linear-slop*) 0.5 0.5 0.5 0.5 :friction mu))
         (v0 0d0) (t0 0d0) (v1 0d0) (t1 0d0)
         (wall (drive world 1.5d0 (lambda (time)
                                    (let ((v (float (physics-body-velocity world box) 1d0)))
                                      (when (<= time 0.5d0) (setf v0 v t0 time))
                                      (setf v1 v t1 time))))))
    (values (/ (- v1 v0) (- t1 t0)) (* g (- (sin theta) (* mu (cos theta)))) wall world)))

(define-accuracy-scene box-incline ("acceleration error along the slope, relative" 0.01 :peers nil)
  "A unit cube sliding down a tilted-gravity incline, tan theta 0.7, friction 0.5: its
acceleration's error against g (sin theta - mu cos theta), relative. #BXPREC"
  (multiple-value-bind (a want wall world) (box-incline-run world-args)
    (values (/ (abs (- a want)) want) wall world
            (format nil "a = ~,5F m/s^2, g(sin - mu cos) = ~,5F" a want))))

(defun box-seams-run (world-args &key (v0 5d0) (after 0.5d0))
  "A frictionless unit cube sliding at V0 along x over the floor of open-air-world for 8 s under
WORLD-ARGS: its largest vertical speed and its largest loss of horizontal speed after AFTER
seconds, the wall seconds and the world. #BXPREC"
  (let* ((world (apply #'open-air-world :floor t world-args))
         (box (add-physics-box world -11.5 (- 0.5 *physics-linear-slop*) 0.5 0.5 0.5 0.5
                               :friction 0.0 :vx v0))
         (rise 0d0) (loss 0d0)
         (wall (drive world 8d0 (lambda (time)
                                  (when (> time after)
                                    (multiple-value-bind (vx vy vz) (physics-body-velocity world box)
                                      (setf rise (max rise (abs vy))
                                            loss (max loss (- v0 (sqrt (+ (* vx vx) (* vz vz))))))))))))
    (values rise loss wall world)))

(define-accuracy-scene box-seams ("worst of vertical speed and speed lost, / v0" 0.001 :peers nil)
  "A frictionless unit cube sliding at 5 m/s across 37 cell seams: the worse of its largest
vertical speed and its largest loss of speed, over 5 m/s. #BXPREC"
  (multiple-value-bind (rise loss wall world) (box-seams-run world-args)
    (values (/ (max rise loss) 5d0) wall world
            (format nil "vertical speed up to ~,3F mm/s, speed lost up to ~,3F mm/s"
                    (* 1000 rise) (* 1000 loss)))))
;; A box on an incline and a box across the seams:1 ends here

;; [[file:../physics.org::#P33R5X][Error against run time, engine beside engine:1]]
(defun peer-run (&key (gravity '(0 -9.81 0)) (seconds 1) sleep record-all boxes balls params)
  "One run of a peer scene as a plist: GRAVITY, SECONDS, SLEEP, RECORD-ALL, BOXES (each a list
x0 y0 z0 x1 y1 z1), BALLS (each a plist of peer-ball) and PARAMS, a plist the measurement
reads. #P33R5X"
  (list :gravity gravity :seconds seconds :sleep sleep :record-all record-all
        :boxes boxes :balls balls :params params))

(defun peer-ball (x y z &key (radius 0.25) (mass 1.0) (restitution 0.0) (friction 0.6) (rolling 0.0)
                          (vx 0.0) (vy 0.0) (vz 0.0) (wx 0.0) (wy 0.0) (wz 0.0) lift watch)
  "A ball of a peer run: its centre, material, velocity and spin; LIFT, its centre lies the
engine's resting overlap lower; WATCH, it is recorded every step. #P33R5X"
  (list :x x :y y :z z :radius radius :mass mass :restitution restitution :friction friction
        :rolling rolling :vx vx :vy vy :vz vz :wx wx :wy wy :wz wz :lift lift :watch watch))

(defparameter +open-floor+ '(-16 -1 -16 32 0 32)
  "The floor of open-air-world as a box. #P33R5X")

(defparameter +lone-cell+ '(0 0 0 1 1 1)
  "The lone cell of drop-onto-block as a box. #P33R5X")

(defparameter +shaft-boxes+ '((-1 -1 -1 2 0 2) (-1 0 -1 0 12 2) (1 0 -1 2 12 2) (0 0 -1 1 12 0) (0 0 1 1 12 2))
  "The cells around make-shaft-world's shaft, as its floor and four walls 12 high. #P33R5X")

(defparameter +basin-boxes+ '((-8 -1 -8 16 0 16) (-1 0 -1 9 6 0) (-1 0 8 9 6 9) (-1 0 0 0 6 8) (8 0 0 9 6 8))
  "The floor and walls of the basin (make-basin-terrain) as boxes. #P33R5X")

(defun bounce-series-seconds (restitution drop)
  "How long a ball of RESTITUTION dropped DROP metres flies, in ideal bounces, to its fifth apex,
and a fifth of a second more; at most 12 s. #P33R5X"
  (let ((t0 (sqrt (/ (* 2 drop) 9.81d0))))
    (min 12d0 (+ 0.2d0 (* t0 (+ 1 (* 2 (loop for k from 1 to 4 sum (expt restitution k)))))))))

(defun peer-scene-runs (scene)
  "The runs of the accuracy scene SCENE, as data: the same balls, boxes and durations as the
scene's function, in the order it adds them. #P33R5X"
  (let ((r 0.25))
    (ecase scene
      (free-fall (list (peer-run :balls (list (peer-ball 0.5 0.0 0.5 :watch t)))))
      (bounce (list (peer-run :seconds 4 :boxes (list +open-floor+)
                              :balls (list (peer-ball 0.5 (+ 2.0 r) 0.5 :restitution 0.8 :watch t)))))
      (slide-to-roll (list (peer-run :boxes (list +open-floor+)
                                     :balls (list (peer-ball 0.5 r 0.5 :friction 0.4 :vx 4.0 :lift t :watch t))
                                     :params '(:v0 4d0 :mu 0.4d0))))
      (rolling-resistance (list (peer-run :seconds 2 :boxes (list +open-floor+)
                                          :balls (list (peer-ball 0.5 r 0.5 :rolling 0.05 :vx 2.0 :wz (/ -2.0 r) :lift t :watch t))
                                          :params '(:v0 2d0 :rho 0.05d0))))
      (seams (list (peer-run :seconds 3 :boxes (list +open-floor+)
                             :balls (list (peer-ball 0.5 r 0.5 :vx 3.0 :lift t :watch t)))))
      (resting (list (peer-run :seconds 3 :sleep t :boxes (list +open-floor+)
                               :balls (list (peer-ball 0.5 (+ r 0.2) 0.5 :watch t)))))
      (head-on (list (peer-run :gravity '(0 0 0)
                               :balls (list (peer-ball -1.0 0.5 0.5 :mass 1.0 :restitution 0.5 :vx 3.0)
                                            (peer-ball 1.0 0.5 0.5 :mass 2.0 :restitution 0.5 :vx -3.0)))))
      (shaft-stack (list (peer-run :seconds 10 :sleep t :boxes +shaft-boxes+
                                   :balls (loop for i below 6 collect (peer-ball 0.5 (+ 0.45 (* i 2.02 0.45)) 0.5 :radius 0.45)))))
      (pile (let ((world (make-basin-world 1000 :sleep t)))
              (list (peer-run :seconds 4 :sleep t :record-all t :boxes +basin-boxes+
                              :balls (loop for h in (physics-world-handles world)
                                           collect (multiple-value-bind (x y z) (physics-body-position world h)
                                                     (peer-ball x y z)))))))
      (bounce-series (loop for e in +bounce-restitutions+
                           nconc (loop for drop in +bounce-drops+
                                       collect (peer-run :seconds (bounce-series-seconds e drop) :boxes (list +open-floor+)
                                                         :balls (list (peer-ball 0.5 (+ r drop) 0.5 :restitution e :lift t :watch t))
                                                         :params (list :restitution e :drop drop)))))
      (cradle (list (peer-run :gravity '(0 0 0)
                              :balls (append (loop for i from 1 below 5
                                                   collect (peer-ball (+ 2.0 (* i 2 r)) 0.5 0.5 :restitution 1.0 :friction 0.0 :watch t))
                                             (list (peer-ball 2.0 0.5 0.5 :restitution 1.0 :friction 0.0 :vx 2.0 :watch t)))
                              :params '(:speed 2d0))))
      (struck-row (list (peer-run :boxes (list +open-floor+)
                                  :balls (append (loop for i from 1 below 4
                                                       collect (peer-ball (+ 2.0 (* i 2 r)) r 0.5 :restitution 1.0 :lift t :watch t))
                                                 (list (peer-ball 0.5 r 0.5 :restitution 1.0 :vx (* 7/5 3.0) :lift t :watch t)))
                                  :params '(:speed 3d0))))
      ((edge-drop corner-drop)
       (loop for speed in '(2d0 5d0 10d0)
             nconc (loop for offset in '(0.05d0 0.1d0 0.15d0 0.2d0)
                         collect (let* ((dx (if (eq scene 'corner-drop) (* 0.7d0 offset) offset))
                                        (dz (if (eq scene 'corner-drop) dx 0d0))
                                        (y0 (nth-value 1 (block-drop-ideal speed dx dz r 0.5d0))))
                                   (peer-run :seconds 0.5 :boxes (list +lone-cell+)
                                             :balls (list (peer-ball (+ 1d0 dx) y0 (if (eq scene 'corner-drop) (+ 1d0 dz) 0.5d0)
                                                                     :friction 0.0 :restitution 0.5 :vy (- speed) :watch t))
                                             :params (list :speed speed :dx dx :dz dz))))))
      (oblique-pair
       (loop for speed in '(2d0 5d0 10d0)
             nconc (loop for offset in '(0.1d0 0.2d0 0.3d0 0.4d0)
                         collect (peer-run :seconds 0.5 :sleep t :gravity '(0 0 0)
                                           :balls (list (peer-ball 0.0d0 (+ 0.5d0 offset) 0.5d0 :friction 0.0 :restitution 0.5 :vx speed)
                                                        (peer-ball 1.0d0 0.5d0 0.5d0 :friction 0.0 :restitution 0.5))
                                           :params (list :speed speed :offset offset))))))))

(defun write-peer-scenes (path &optional (scenes (mapcar #'first *accuracy-scenes*)))
  "Write the runs of SCENES to PATH in the scene file's format (tools/peers/scenes.h). #P33R5X"
  (with-open-file (out path :direction :output :if-exists :supersede)
    (let ((*read-default-float-format* 'double-float))
      (flet ((num (x) (format nil "~F" (float x 1d0))))
        (dolist (scene scenes)
          (format out "scene ~(~A~)~%" scene)
          (dolist (run (peer-scene-runs scene))
            (format out "run~%gravity ~{~A~^ ~}~%seconds ~A~%sleep ~D~%record-all ~D~%"
                    (mapcar #'num (getf run :gravity)) (num (getf run :seconds))
                    (if (getf run :sleep) 1 0) (if (getf run :record-all) 1 0))
            (dolist (b (getf run :boxes)) (format out "box ~{~A~^ ~}~%" (mapcar #'num b)))
            (dolist (b (getf run :balls))
              (format out "ball ~{~A~^ ~} ~D ~D~%"
                      (mapcar (lambda (k) (num (getf b k))) '(:x :y :z :radius :mass :restitution :friction :rolling :vx :vy :vz :wx :wy :wz))
                      (if (getf b :lift) 1 0) (if (getf b :watch) 1 0)))
            (loop for (k v) on (getf run :params) by #'cddr do (format out "param ~(~A~) ~A~%" k (num v)))
            (format out "end~%"))))))
  path)

(defun read-peer-scenes (path)
  "The scene file at PATH as an alist of scene names (symbols of this package) to their runs,
the plists peer-scene-runs makes, its numbers double-floats. #P33R5X"
  (let ((scenes '()) (runs nil) (run nil) (name nil))
    (flet ((numbers (words) (let ((*read-default-float-format* 'double-float) (*read-eval* nil))
                              (mapcar (lambda (w) (float (read-from-string w) 1d0)) words)))
           (close-scene () (when name (push (cons name (nreverse runs)) scenes))))
      (with-open-file (in path)
        (loop for line = (read-line in nil) while line
              for words = (uiop:split-string (string-trim " " line) :separator " ")
              for head = (first words)
              do (cond ((string= head "scene") (close-scene) (setf name (intern (string-upcase (second words)) '#:luv-physics) runs '()))
                       ((string= head "run") (setf run (peer-run)))
                       ((string= head "gravity") (setf (getf run :gravity) (numbers (rest words))))
                       ((string= head "seconds") (setf (getf run :seconds) (first (numbers (rest words)))))
                       ((string= head "sleep") (setf (getf run :sleep) (string= (second words) "1")))
                       ((string= head "record-all") (setf (getf run :record-all) (string= (second words) "1")))
                       ((string= head "box") (setf (getf run :boxes) (append (getf run :boxes) (list (numbers (rest words))))))
                       ((string= head "ball")
                        (destructuring-bind (x y z radius mass e mu rho vx vy vz wx wy wz lift watch) (numbers (rest words))
                          (setf (getf run :balls)
                                (append (getf run :balls)
                                        (list (peer-ball x y z :radius radius :mass mass :restitution e :friction mu :rolling rho
                                                               :vx vx :vy vy :vz vz :wx wx :wy wy :wz wz
                                                               :lift (= lift 1) :watch (= watch 1)))))))
                       ((string= head "param")
                        (setf (getf run :params) (append (getf run :params)
                                                         (list (intern (string-upcase (second words)) :keyword)
                                                               (first (numbers (cddr words)))))))
                       ((string= head "end") (push run runs))
                       ((string= head ""))
                       (t (error "read-peer-scenes: unknown directive ~S in ~A" head path)))))
      (close-scene))
    (nreverse scenes)))
;; Error against run time, engine beside engine:1 ends here

;; [[file:../physics.org::#P33R5X][Error against run time, engine beside engine:2]]
(defstruct (peer-trace (:constructor make-peer-trace (frames watched balls wall record-all times watch all final)))
  "One run's record: FRAMES frames (the first before any step) of TIMES, the WATCH columns of the
WATCHED balls (x y z vx vy vz wx wy wz each), ALL balls' centres when RECORD-ALL, the FINAL
positions and velocities of the BALLS, and the WALL seconds of the steps. #P33R5X"
  (frames 0 :type fixnum) (watched 0 :type fixnum) (balls 0 :type fixnum) (wall 0d0 :type double-float)
  (record-all nil) (times nil) (watch nil) (all nil) (final nil))

(defun parse-peer-traces (data)
  "The traces in DATA, a vector of double-floats laid out as tools/peers/scenes.h writes them. #P33R5X"
  (let ((at 0) (traces '()))
    (flet ((take (n) (prog1 (subseq data at (+ at n)) (incf at n))))
      (loop while (< at (length data))
            do (destructuring-bind (frames watched balls wall record-all) (coerce (take 5) 'list)
                 (let* ((frames (round frames)) (watched (round watched)) (balls (round balls))
                        (record-all (= record-all 1d0))
                        (per (+ 1 (* 9 watched) (if record-all (* 3 balls) 0)))
                        (times (make-array frames :element-type 'double-float))
                        (watch (make-array (* frames watched 9) :element-type 'double-float))
                        (all (and record-all (make-array (* frames balls 3) :element-type 'double-float))))
                   (dotimes (f frames)
                     (let ((base (+ at (* f per))))
                       (setf (aref times f) (aref data base))
                       (replace watch data :start1 (* f watched 9) :start2 (1+ base) :end2 (+ 1 base (* 9 watched)))
                       (when all (replace all data :start1 (* f balls 3) :start2 (+ 1 base (* 9 watched)) :end2 (+ base per)))))
                   (incf at (* frames per))
                   (push (make-peer-trace frames watched balls wall record-all times watch all
                                          (coerce (take (* 6 balls)) '(simple-array double-float (*))))
                         traces)))))
    (nreverse traces)))

(defun read-peer-output (path)
  "The little-endian doubles of the file at PATH, as a vector of double-floats. #P33R5X"
  (with-open-file (in path :element-type '(unsigned-byte 64))
    (let* ((words (make-array (file-length in) :element-type '(unsigned-byte 64)))
           (data (make-array (length words) :element-type 'double-float)))
      (read-sequence words in)
      (dotimes (i (length words) data)
        (let ((w (aref words i)))
          (setf (aref data i) (sb-kernel:make-double-float (let ((hi (ldb (byte 32 32) w))) (if (>= hi #x80000000) (- hi #x100000000) hi))
                                                           (ldb (byte 32 0) w))))))))

(defun trace-watch (trace frame ball column)
  "Column COLUMN (0 to 8: x y z vx vy vz wx wy wz) of watched ball BALL at FRAME of TRACE. #P33R5X"
  (aref (peer-trace-watch trace) (+ column (* 9 (+ ball (* frame (peer-trace-watched trace)))))))

(defun trace-final (trace ball column)
  "Column COLUMN (0 to 5: x y z vx vy vz) of ball BALL after TRACE's last step. #P33R5X"
  (aref (peer-trace-final trace) (+ column (* 6 ball))))
;; Error against run time, engine beside engine:2 ends here

;; [[file:../physics.org::#P33R5X][Error against run time, engine beside engine:3]]
(defun run-peer-scene-here (runs hz substeps &key (kernels :scalar))
  "Run the RUNS of a peer scene in this engine at HZ and SUBSTEPS with KERNELS, recording what
the harnesses record; return the traces, as parse-peer-traces reads them. #P33R5X"
  (let ((data (make-array 1024 :element-type 'double-float :adjustable t :fill-pointer 0)))
    (flet ((put (x) (vector-push-extend (float x 1d0) data)))
      (dolist (run runs)
        (let* ((terrain (make-voxel-terrain))
               (world (progn (fill-terrain terrain -16 -16 -16 32 32 32 nil)
                             (dolist (b (getf run :boxes)) (apply #'fill-terrain terrain (append (mapcar #'round b) '(t))))
                             (make-physics-world :terrain terrain :gravity (getf run :gravity) :step-seconds (/ 1 hz)
                                                 :substeps substeps :kernels kernels :sleep (getf run :sleep))))
               (balls (loop for b in (getf run :balls)
                            collect (add-physics-body world (getf b :x) (if (getf b :lift) (- (getf b :y) *physics-linear-slop*) (getf b :y)) (getf b :z)
                                                      :radius (getf b :radius) :mass (getf b :mass) :restitution (getf b :restitution)
                                                      :friction (getf b :friction) :rolling-resistance (getf b :rolling)
                                                      :vx (getf b :vx) :vy (getf b :vy) :vz (getf b :vz))
                            into handles
                            do (unless (every #'zerop (list (getf b :wx) (getf b :wy) (getf b :wz)))
                                 (set-physics-body-angular-velocity world (car (last handles)) (getf b :wx) (getf b :wy) (getf b :wz)))
                            finally (return handles)))
               (watched (loop for b in (getf run :balls) for h in balls when (getf b :watch) collect h))
               (dt (float (physics-world-step-seconds world) 1d0))
               (steps (round (getf run :seconds) dt))
               (frames (make-array 1024 :element-type 'double-float :adjustable t :fill-pointer 0))
               (wall 0d0))
          (flet ((frame (time)
                   (vector-push-extend time frames)
                   (dolist (h watched)
                     (multiple-value-bind (x y z) (physics-body-position world h)
                       (multiple-value-bind (vx vy vz) (physics-body-velocity world h)
                         (multiple-value-bind (wx wy wz) (physics-body-angular-velocity world h)
                           (dolist (v (list x y z vx vy vz wx wy wz)) (vector-push-extend (float v 1d0) frames))))))
                   (when (getf run :record-all)
                     (dolist (h balls)
                       (multiple-value-bind (x y z) (physics-body-position world h)
                         (vector-push-extend (float x 1d0) frames) (vector-push-extend (float y 1d0) frames)
                         (vector-push-extend (float z 1d0) frames))))))
            (frame 0d0)
            (dotimes (i steps)
              (step-physics-world world)
              (incf wall (physics-world-last-step-real-seconds world))
              (frame (* (1+ i) dt)))
            (dolist (x (list (1+ steps) (length watched) (length balls) wall (if (getf run :record-all) 1 0))) (put x))
            (loop for x across frames do (vector-push-extend x data))
            (dolist (h balls)
              (multiple-value-bind (x y z) (physics-body-position world h)
                (multiple-value-bind (vx vy vz) (physics-body-velocity world h)
                  (dolist (v (list x y z vx vy vz)) (put v)))))))))
    (parse-peer-traces (coerce data '(simple-array double-float (*))))))
;; Error against run time, engine beside engine:3 ends here

;; [[file:../physics.org::#P33R5X][Error against run time, engine beside engine:4]]
(defvar *peer-measures* '()
  "Each scene's measurement: (SCENE . FUNCTION), FUNCTION of the runs, their traces and the
engine's resting overlap SLOP, returning the error and a note. #P33R5X")

(defmacro define-peer-measure (scene (runs traces slop) doc &body body)
  "Define how SCENE's error is measured, as the function PEER-MEASURE-SCENE of its RUNS, their
TRACES and the resting overlap SLOP of the engine that ran them; DOC is its docstring. #P33R5X"
  (let ((function (intern (format nil "PEER-MEASURE-~A" scene))))
    `(progn
       (defun ,function (,runs ,traces ,slop)
         ,doc
         (declare (ignorable ,runs ,traces ,slop))
         ,@body)
       (setf *peer-measures* (append (remove ',scene *peer-measures* :key #'first) (list (cons ',scene ',function))))
       ',scene)))

(defun trace-step (trace)
  "The step of TRACE, s: the time of its second frame. #P33R5X"
  (aref (peer-trace-times trace) 1))

(define-peer-measure free-fall (runs traces slop)
  "The largest distance of the ball from y = -g t^2/2 (accuracy-scene-free-fall). #P33R5X"
  (let ((tr (first traces)))
    (values (loop for f from 1 below (peer-trace-frames tr)
                  for time = (aref (peer-trace-times tr) f)
                  maximize (abs (+ (trace-watch tr f 0 1) (* 0.5d0 9.81d0 time time))))
            "")))

(define-peer-measure bounce (runs traces slop)
  "The worst relative error of the first three apexes against 0.8^(2n) times 2 m (accuracy-scene-bounce). #P33R5X"
  (let ((tr (first traces)) (r 0.25d0) (apexes '()) (rising nil))
    (loop for f from 1 below (peer-trace-frames tr)
          for vy = (trace-watch tr f 0 4)
          do (when (and rising (<= vy 0)) (push (- (trace-watch tr f 0 1) r) apexes))
             (setf rising (> vy 0)))
    (setf apexes (reverse apexes))
    (values (if (< (length apexes) 3)
                1d0
                (loop for n from 1 to 3 for h in apexes
                      maximize (let ((ideal (* 2d0 (expt 0.8d0 (* 2 n))))) (/ (abs (- h ideal)) ideal))))
            (format nil "apexes ~{~,3F~^ ~} m" (subseq apexes 0 (min 3 (length apexes)))))))

(define-peer-measure slide-to-roll (runs traces slop)
  "The largest speed error over v0 against sliding, then rolling at 5/7 v0 (accuracy-scene-slide-to-roll). #P33R5X"
  (let* ((tr (first traces)) (params (getf (first runs) :params))
         (r 0.25d0) (v0 (getf params :v0)) (mu (getf params :mu)) (g 9.81d0)
         (t-roll (/ (* 2 v0) (* 7 mu g))) (began nil) (worst 0d0))
    (loop for f from 1 below (peer-trace-frames tr)
          for time = (aref (peer-trace-times tr) f)
          for vx = (trace-watch tr f 0 3)
          do (let ((ideal (if (< time t-roll) (- v0 (* mu g time)) (* 5/7 v0))))
               (setf worst (max worst (/ (abs (- vx ideal)) v0)))
               (when (and (not began) (< (abs (+ vx (* (trace-watch tr f 0 8) r))) 0.01))
                 (setf began time))))
    (values worst (format nil "rolling from ~:[never~;~:*~,3F s~] (ideal ~,3F s)" began t-roll))))

(define-peer-measure rolling-resistance (runs traces slop)
  "The largest speed error over v0 against v0 - 5/7 rho g t (accuracy-scene-rolling-resistance). #P33R5X"
  (let* ((tr (first traces)) (params (getf (first runs) :params))
         (v0 (getf params :v0)) (rho (getf params :rho)))
    (values (loop for f from 1 below (peer-trace-frames tr)
                  for time = (aref (peer-trace-times tr) f)
                  maximize (/ (abs (- (trace-watch tr f 0 3) (max 0d0 (- v0 (* 5/7 rho 9.81d0 time))))) v0))
            (format nil "speed at the end ~,3F m/s (ideal ~,3F)" (trace-watch tr (1- (peer-trace-frames tr)) 0 3)
                    (max 0d0 (- v0 (* 5/7 rho 9.81d0 (aref (peer-trace-times tr) (1- (peer-trace-frames tr))))))))))

(defun trace-speed (trace frame ball)
  "The speed of watched ball BALL at FRAME of TRACE. #P33R5X"
  (sqrt (+ (expt (trace-watch trace frame ball 3) 2) (expt (trace-watch trace frame ball 4) 2) (expt (trace-watch trace frame ball 5) 2))))

(define-peer-measure seams (runs traces slop)
  "The largest distance of the centre from its resting height after 0.5 s (accuracy-scene-seams). #P33R5X"
  (let* ((tr (first traces)) (rest (- 0.25d0 slop)) (worst 0d0) (v1 nil) (v3 0d0))
    (loop for f from 1 below (peer-trace-frames tr)
          for time = (aref (peer-trace-times tr) f)
          do (when (>= time 0.5) (setf worst (max worst (abs (- (trace-watch tr f 0 1) rest)))))
             (when (and (null v1) (>= time 1.0)) (setf v1 (trace-speed tr f 0)))
             (setf v3 (trace-speed tr f 0)))
    (values worst (format nil "speed lost 1-3 s: ~,3F %" (if (plusp v1) (* 100 (/ (- v1 v3) v1)) 0)))))

(define-peer-measure resting (runs traces slop)
  "The largest distance of the depth from SLOP over the third second (accuracy-scene-resting). #P33R5X"
  (let ((tr (first traces)) (r 0.25d0))
    (values (loop for f from 1 below (peer-trace-frames tr)
                  when (>= (aref (peer-trace-times tr) f) 2.0)
                    maximize (abs (- (- r (trace-watch tr f 0 1)) slop)))
            "")))

(define-peer-measure head-on (runs traces slop)
  "The final velocities against -3 and 0 m/s, over the approach speed (accuracy-scene-head-on). #P33R5X"
  (let* ((tr (first traces)) (va (trace-final tr 0 3)) (vb (trace-final tr 1 3)))
    (values (/ (max (abs (- va -3d0)) (abs vb)) 6d0)
            (format nil "momentum ~,4F (ideal -3) kg m/s" (+ va (* 2 vb))))))

(define-peer-measure shaft-stack (runs traces slop)
  "The top ball's distance from its ideal height plus its drift (accuracy-scene-shaft-stack). #P33R5X"
  (let* ((tr (first traces)) (r 0.45d0) (top 5)
         (drop (- (+ (- r slop) (* 5 (- (* 2 r) slop))) (trace-final tr top 1)))
         (drift (sqrt (+ (expt (- (trace-final tr top 0) 0.5) 2) (expt (- (trace-final tr top 2) 0.5) 2)))))
    (values (+ (abs drop) drift) (format nil "top ~,4F m low, ~,4F m aside" drop drift))))

(defun deepest-overlap (centres radii boxes order)
  "The deepest overlap, m, of balls at CENTRES (x y z of each) with RADII between two of them or
with one of BOXES (x0 y0 z0 x1 y1 z1 each); 0 when none overlaps. Pairs are swept in order of
x, ORDER a scratch vector of the balls' indices. #P33R5X"
  (declare (type (simple-array double-float (*)) centres radii) (type (simple-array fixnum (*)) order)
           (optimize speed))
  (let* ((n (length radii)) (reach (* 2 (reduce #'max radii))) (deepest 0d0))
    (declare (type double-float deepest reach) (type fixnum n))
    (dotimes (i n) (setf (aref order i) i))
    (sort order #'< :key (lambda (i) (aref centres (* 3 i))))
    (dotimes (k n)
      (let* ((i (aref order k)) (x (aref centres (* 3 i))) (y (aref centres (+ 1 (* 3 i))))
             (z (aref centres (+ 2 (* 3 i)))) (r (aref radii i)))
        (loop for m of-type fixnum from (1+ k) below n
              for j = (aref order m)
              while (< (- (aref centres (* 3 j)) x) reach)
              do (let ((d (sqrt (+ (expt (- x (aref centres (* 3 j))) 2) (expt (- y (aref centres (+ 1 (* 3 j)))) 2)
                                   (expt (- z (aref centres (+ 2 (* 3 j)))) 2)))))
                   (setf deepest (max deepest (- (+ r (aref radii j)) d)))))
        (dolist (b boxes)
          (destructuring-bind (x0 y0 z0 x1 y1 z1) b
            (declare (type double-float x0 y0 z0 x1 y1 z1))
            (let ((dx (max (- x0 x) 0d0 (- x x1))) (dy (max (- y0 y) 0d0 (- y y1))) (dz (max (- z0 z) 0d0 (- z z1))))
              (setf deepest (max deepest (if (and (zerop dx) (zerop dy) (zerop dz))
                                             (+ r (min (- x x0) (- x1 x) (- y y0) (- y1 y) (- z z0) (- z1 z)))
                                             (- r (sqrt (+ (* dx dx) (* dy dy) (* dz dz))))))))))))
    deepest))

(defvar *peer-pile-reference* nil
  "The pile's energy as this engine's converged run (240 Hz, 16 substeps) of the peer scene
ends it, once computed. #P33R5X")

(defun trace-pile-energy (trace)
  "The potential (above y = 0) and kinetic energy of TRACE's 1 kg balls at its end, J. #P33R5X"
  (loop for i below (peer-trace-balls trace)
        sum (+ (* 9.81d0 (trace-final trace i 1))
               (* 0.5d0 (+ (expt (trace-final trace i 3) 2) (expt (trace-final trace i 4) 2) (expt (trace-final trace i 5) 2))))))

(defun peer-pile-reference (runs)
  "*peer-pile-reference*, computed from RUNS when not yet known. #P33R5X"
  (or *peer-pile-reference*
      (setf *peer-pile-reference* (trace-pile-energy (first (run-peer-scene-here runs 240 16))))))

(define-peer-measure pile (runs traces slop)
  "The worse of the energy's error against this engine's converged run and the deepest overlap over the radius (accuracy-scene-pile). #P33R5X"
  (let* ((tr (first traces)) (run (first runs)) (n (peer-trace-balls tr))
         (radii (map '(simple-array double-float (*)) (lambda (b) (float (getf b :radius) 1d0)) (getf run :balls)))
         (boxes (mapcar (lambda (b) (mapcar (lambda (x) (float x 1d0)) b)) (getf run :boxes)))
         (centres (make-array (* 3 n) :element-type 'double-float))
         (order (make-array n :element-type 'fixnum))
         (deepest (loop for f from 1 below (peer-trace-frames tr)
                        do (replace centres (peer-trace-all tr) :start2 (* f n 3))
                        maximize (deepest-overlap centres radii boxes order)))
         (reference (peer-pile-reference runs))
         (energy (trace-pile-energy tr))
         (energy-error (/ (abs (- energy reference)) reference)))
    (values (max energy-error (/ deepest 0.25d0))
            (format nil "deepest ~,4F m; energy ~,1F J against ~,1F J (~,2,,,,,'eE)" deepest energy reference energy-error))))

(define-peer-measure bounce-series (runs traces slop)
  "The worst relative error of a rebound ratio against e^2 (accuracy-scene-bounce-series, rebound-heights). #P33R5X"
  (let ((worst 0d0) (count 0) (g 9.81d0) (limit (* 1.1d0 *physics-restitution-threshold*)))
    (loop for run in runs for tr in traces
          do (let* ((params (getf run :params)) (e (getf params :restitution))
                    (level (- 0.25d0 slop)) (dt (trace-step tr)) (apexes '()) (flying nil))
               (loop for f from 2 below (peer-trace-frames tr)
                     while (<= (length apexes) 4)
                     do (let ((y0 (trace-watch tr (- f 2) 0 1)) (y1 (trace-watch tr (- f 1) 0 1)) (y2 (trace-watch tr f 0 1)))
                          (let ((free (< (abs (+ (- y0 (* 2 y1)) y2 (* g dt dt))) 1d-5)))
                            (when (and free (not flying))
                              (let ((b (+ (/ (- y1 y0) dt) (* 0.5d0 g dt))))
                                (push (- (+ y0 (/ (* b (abs b)) (* 2 g))) level) apexes)))
                            (setf flying free))))
               (let* ((heights (reverse apexes)) (e2 (* e e))
                      (errors (loop for (before after) on heights while after
                                    while (> (sqrt (* 2 g (max 0d0 before))) limit)
                                    collect (/ (abs (- (/ after before) e2)) e2))))
                 (incf count (length errors))
                 (setf worst (reduce #'max errors :initial-value (if errors worst 1d0))))))
    (values worst (format nil "~D rebounds" count))))

(defun struck-row-measure (runs traces)
  "The worse of the momentum share and the energy the last ball of a struck row does not carry,
at the frame it is fastest; the watched balls are the row, then the striker. #P33R5X"
  (let* ((tr (first traces)) (speed (getf (getf (first runs) :params) :speed))
         (k (peer-trace-watched tr)) (best nil))
    (loop for f from 1 below (peer-trace-frames tr)
          for vs = (cons (trace-watch tr f (1- k) 3) (loop for j below (1- k) collect (trace-watch tr f j 3)))
          do (when (or (null best) (> (car (last vs)) (car (last best)))) (setf best vs)))
    (let ((share (if (plusp (reduce #'+ best)) (/ (car (last best)) (reduce #'+ best)) 0d0))
          (kept (/ (reduce #'+ (mapcar (lambda (v) (* v v)) best)) (* speed speed)))
          (others (/ (reduce #'max (mapcar #'abs (butlast best))) speed)))
      (values (max (- 1 share) (- 1 kept)) (format nil "others ~,3F v0, energy ~,3F" others kept)))))

(define-peer-measure cradle (runs traces slop)
  "The momentum and energy the last ball does not carry (accuracy-scene-cradle). #P33R5X"
  (struck-row-measure runs traces))

(define-peer-measure struck-row (runs traces slop)
  "The momentum and energy the last ball does not carry (accuracy-scene-struck-row). #P33R5X"
  (struck-row-measure runs traces))

(defun angle-between (a b)
  "The angle, degrees, between the vectors A and B (lists of three); 180 when either is zero, as
when a striker passes through the ball it should strike. #P33R5X"
  (if (or (every #'zerop a) (every #'zerop b))
      180d0
      (let ((c (/ (reduce #'+ (mapcar #'* a b)) (sqrt (* (reduce #'+ (mapcar #'* a a)) (reduce #'+ (mapcar #'* b b)))))))
        (* (/ 180 pi) (acos (max -1d0 (min 1d0 c)))))))

(defun block-drop-measure (runs traces)
  "The largest angle of a block drop's impulse from the geometric normal at impact, and of its
outgoing velocity from the reflection law's (drop-onto-block), over RUNS. #P33R5X"
  (let ((impulse 0d0) (outgoing 0d0) (g 9.81d0))
    (loop for run in runs for tr in traces
          do (destructuring-bind (&key speed dx dz) (getf run :params)
               (multiple-value-bind (y-impact y0 t-impact n v-in ideal) (block-drop-ideal speed dx dz 0.25d0 0.5d0)
                 (declare (ignore y-impact y0))
               (let ((hit nil) (out nil))
                 (loop for f from 1 below (peer-trace-frames tr) until out
                       for time = (aref (peer-trace-times tr) f)
                       do (let ((vx (trace-watch tr f 0 3)) (vy (trace-watch tr f 0 4)) (vz (trace-watch tr f 0 5)))
                            (cond ((and (not hit) (> (abs (- vy (- (- speed) (* g time)))) 1d-3)) (setf hit f))
                                  ((and hit (> f (1+ hit))) (setf out (list vx (+ vy (* g (- time t-impact))) vz))))))
                 (setf impulse (max impulse (if out (angle-between (mapcar #'- out v-in) n) 180d0))
                       outgoing (max outgoing (if out (angle-between out ideal) 180d0)))))))
    (values impulse (format nil "outgoing off by up to ~,2F deg" outgoing))))

(define-peer-measure edge-drop (runs traces slop)
  "The largest angle of the impulse from the edge's geometric normal (accuracy-scene-edge-drop). #P33R5X"
  (block-drop-measure runs traces))

(define-peer-measure corner-drop (runs traces slop)
  "The largest angle of the impulse from the corner's geometric normal (accuracy-scene-corner-drop). #P33R5X"
  (block-drop-measure runs traces))

(define-peer-measure oblique-pair (runs traces slop)
  "The largest angle of the struck ball's velocity from the line of centres (accuracy-scene-oblique-pair). #P33R5X"
  (let ((impulse 0d0) (outgoing 0d0) (reach 0.5d0) (e 0.5d0))
    (loop for run in runs for tr in traces
          do (destructuring-bind (&key speed offset) (getf run :params)
               (let* ((n (list (/ (sqrt (- (* reach reach) (* offset offset))) reach) (/ (- offset) reach) 0d0))
                      (vn (* speed (first n)))
                      (ideal (list (- speed (* 0.5d0 (+ 1 e) vn (first n))) (- (* 0.5d0 (+ 1 e) vn (second n))) 0d0)))
                 (setf impulse (max impulse (angle-between (loop for c from 3 to 5 collect (trace-final tr 1 c)) n))
                       outgoing (max outgoing (angle-between (loop for c from 3 to 5 collect (trace-final tr 0 c)) ideal))))))
    (values impulse (format nil "striker off by up to ~,2F deg" outgoing))))

(defun measure-peer-scene (scene runs traces slop)
  "SCENE's error and note from the TRACES of its RUNS, run by an engine of resting overlap SLOP;
an error of 10^9 when the traces hold numbers the measurement cannot take (a peer's balls gone to
infinity, say), with the note saying so. #P33R5X"
  (handler-case (funcall (cdr (or (assoc scene *peer-measures*) (error "no measurement for ~S" scene))) runs traces slop)
    (arithmetic-error (e) (values 1d9 (format nil "not measurable: ~A" e)))))
;; Error against run time, engine beside engine:4 ends here

;; [[file:../physics.org::#P33R5X][Error against run time, engine beside engine:7]]
(defun peer-file (name)
  "The pathname of the file NAME of the repository. #P33R5X"
  (asdf:system-relative-pathname "luv-physics" name))

(defun run-peer-harness (program arguments)
  "Run PROGRAM with ARGUMENTS; return its error output and exit code. #P33R5X"
  (let* ((err (make-string-output-stream))
         (process (sb-ext:run-program program arguments :output nil :error err :input nil)))
    (values (get-output-stream-string err) (sb-ext:process-exit-code process))))

(defparameter +peer-rates+ '(30 60 120 240)
  "Step rates of every engine's curves, Hz. #P33R5X")

(defun peer-curves ()
  "The curves of the comparison, each (ENGINE LABEL SUBSTEPS ITERATIONS KNOBS): this engine at
1, 2, 4 and 8 substeps; Bullet at 4, 10 and 30 iterations with margin 0, at its defaults
(margin 0.04) and without split impulse; ODE's quick step at 5, 20 and 80 iterations and its
big-matrix dWorldStep; Box3D, when its harness was built, at 1, 4 (its default) and 8 substeps.
Each runs at every rate of +peer-rates+. #P33R5X"
  (append (loop for n in '(1 2 4 8) collect (list :luv (format nil "this engine, ~D substeps" n) n 1 '()))
          (loop for i in '(4 10 30) collect (list :bullet (format nil "Bullet, ~D iterations" i) 1 i '("margin=0")))
          (list (list :bullet "Bullet defaults (margin 0.04)" 1 10 '("margin=0.04"))
                (list :bullet "Bullet, no split impulse" 1 10 '("margin=0" "split=0")))
          (loop for i in '(5 20 80) collect (list :ode (format nil "ODE quick step, ~D iterations" i) 1 i '()))
          (list (list :ode "ODE dWorldStep" 1 1 '("solver=step")))
          (when (peer-binary :box3d)
            (loop for n in '(1 4 8) collect (list :box3d (format nil "Box3D, ~D substeps" n) n 1 '())))))

(defun peer-binary (engine)
  "The harness of ENGINE (:bullet, :ode or :box3d): report/peers/ENGINE-scenes when it exists. #P33R5X"
  (let ((path (peer-file (format nil "report/peers/~(~A~)-scenes" engine))))
    (and (probe-file path) path)))

(defun run-peer-point (engine scene runs scenes-file hz substeps iterations knobs)
  "Run SCENE's RUNS (read from SCENES-FILE) in ENGINE at HZ, SUBSTEPS, ITERATIONS and KNOBS;
return its traces. #P33R5X"
  (if (eq engine :luv)
      (run-peer-scene-here runs hz substeps :kernels (car (last (available-kernel-families))))
      (let ((out (peer-file (format nil "report/peers/~(~A~)-~D.bin" engine (sb-unix:unix-getpid)))))
        (multiple-value-bind (stderr code)
            (run-peer-harness (namestring (peer-binary engine))
                            (list* (namestring scenes-file) (string-downcase (symbol-name scene))
                                   (princ-to-string hz) (princ-to-string substeps) (princ-to-string iterations)
                                   (format nil "~F" (peer-point-slop engine)) (namestring out) knobs))
          (unless (zerop code) (error "~(~A~) harness failed on ~(~A~): ~A" engine scene stderr)))
        (let ((traces (prog1 (parse-peer-traces (read-peer-output out)) (delete-file out))))
          (check-peer-traces engine scene runs traces)
          traces))))

(defun check-peer-traces (engine scene runs traces)
  "Signal an error unless TRACES, ENGINE's record of SCENE's RUNS, has a trace per run with the
run's balls and watched balls, each watched ball starting where the run puts it (lifted by the
engine's slop) within 10^-5 m: the harness read the scene file and wrote its record as the page
reads them. #P33R5X"
  (unless (= (length traces) (length runs))
    (error "~(~A~) recorded ~D runs of ~(~A~), not ~D" engine (length traces) scene (length runs)))
  (loop for run in runs for trace in traces
        for balls = (getf run :balls)
        for watched = (remove-if-not (lambda (b) (getf b :watch)) balls)
        do (unless (and (= (peer-trace-balls trace) (length balls)) (= (peer-trace-watched trace) (length watched)))
             (error "~(~A~) recorded ~D balls, ~D watched, of a run of ~(~A~) with ~D, ~D watched"
                    engine (peer-trace-balls trace) (peer-trace-watched trace) scene (length balls) (length watched)))
           (loop for b in watched for j from 0
                 for at = (list (getf b :x) (if (getf b :lift) (- (getf b :y) (peer-point-slop engine)) (getf b :y)) (getf b :z))
                 do (loop for c below 3 for want in at
                          unless (< (abs (- (trace-watch trace 0 j c) want)) 1d-5)
                            do (error "~(~A~) starts a ball of ~(~A~) at ~,6F on axis ~D, not ~,6F"
                                      engine scene (trace-watch trace 0 j c) c want)))))

(defun peer-point-slop (engine)
  "The resting overlap ENGINE's contacts are meant to keep: this engine's linear slop, Box3D's
(B3_LINEAR_SLOP, 0.005 m), 0 for Bullet and ODE. #P33R5X"
  (case engine
    (:luv (float *physics-linear-slop* 1d0))
    (:box3d 0.005d0)
    (t 0d0)))

(defparameter +pile-skipped+
  '("Bullet, 30 iterations" "Bullet, no split impulse" "ODE quick step, 80 iterations" "ODE dWorldStep")
  "The curves the pile leaves out, to keep make report-peers within its minutes. #P33R5X")

(defun run-peer-sweep (&key (scenes (mapcar #'first *accuracy-scenes*)) (scenes-file (peer-file "report/peers/scenes.txt"))
                            (rates +peer-rates+) (curves (peer-curves)) (stream *standard-output*))
  "Every curve of CURVES at every rate of RATES on every scene of SCENES, read from SCENES-FILE;
return a plist per point (:scene :engine :curve :hz :error :ms :note :repeated). Each scene's
points run twice (the pile's, which take seconds each, once), the engines interleaved, and a
point keeps its faster run's time; :repeated says whether the runs ended every ball in the same
place. #P33R5X"
  (let ((file (read-peer-scenes scenes-file)) (points '()))
    (dolist (scene scenes (nreverse points))
      (let* ((runs (cdr (assoc scene file)))
             (seconds (reduce #'+ runs :key (lambda (r) (getf r :seconds))))
             (plan (loop for hz in rates
                         nconc (loop for (engine label substeps iterations knobs) in curves
                                     unless (and (eq scene 'pile) (member label +pile-skipped+ :test #'string=))
                                       collect (list engine label hz substeps iterations knobs))))
             (by-engine (loop for e in '(:luv :bullet :ode :box3d)
                              collect (remove e plan :key #'first :test-not #'eq)))
             (order (loop for k from 0 below (reduce #'max by-engine :key #'length)
                          nconc (loop for l in by-engine when (nth k l) collect (nth k l))))
             (results (make-hash-table :test #'equal)))
        (when (eq scene 'pile) (peer-pile-reference runs))
        (dotimes (pass (if (eq scene 'pile) 1 2))
          (dolist (p order)
            (destructuring-bind (engine label hz substeps iterations knobs) p
              (declare (ignore label))
              (push (run-peer-point engine scene runs scenes-file hz substeps iterations knobs) (gethash p results)))))
        (dolist (p order)
          (destructuring-bind (engine label hz substeps iterations knobs) p
            (declare (ignore substeps iterations knobs))
            (let* ((all (reverse (gethash p results))) (first (first all)))
              (multiple-value-bind (err note) (measure-peer-scene scene runs first (peer-point-slop engine))
                (let ((ms (/ (* 1000 (reduce #'min all :key (lambda (traces) (reduce #'+ traces :key #'peer-trace-wall)))) seconds)))
                  (push (list :scene scene :engine engine :curve label :hz hz :error (float err 1d0) :ms ms :note note
                              :repeated (every (lambda (other) (every (lambda (a b) (equalp (peer-trace-final a) (peer-trace-final b))) first other))
                                               (rest all)))
                        points)
                  (format stream "~&~(~A~) ~A ~D Hz: error ~,3,,,,,'eE, ~,3F ms/s~%" scene label hz err ms))))))))))
;; Error against run time, engine beside engine:7 ends here

;; [[file:../physics.org::#P33R5X][Error against run time, engine beside engine:8]]
(defparameter +engine-styles+ '((:luv "#1e8449" :circle) (:bullet "#c0392b" :square) (:ode "#2471a3" :triangle) (:box3d "#8e44ad" :diamond))
  "Each engine's colour and marker in the diagrams. #P33R5X")

(defparameter +curve-dashes+ '("" "7 3" "2 2" "9 3 2 3" "4 4")
  "The dash patterns of an engine's curves, in the order of its curves. #P33R5X")

(defun svg-marker (out shape x y colour)
  "Write to OUT the marker SHAPE (:circle :square :triangle :diamond) at X Y in COLOUR. #P33R5X"
  (ecase shape
    (:circle (format out "<circle cx=\"~,1F\" cy=\"~,1F\" r=\"3\" fill=\"~A\"/>~%" x y colour))
    (:square (format out "<rect x=\"~,1F\" y=\"~,1F\" width=\"6\" height=\"6\" fill=\"~A\"/>~%" (- x 3) (- y 3) colour))
    (:triangle (format out "<polygon points=\"~,1F,~,1F ~,1F,~,1F ~,1F,~,1F\" fill=\"~A\"/>~%" x (- y 4) (- x 3.5) (+ y 3) (+ x 3.5) (+ y 3) colour))
    (:diamond (format out "<polygon points=\"~,1F,~,1F ~,1F,~,1F ~,1F,~,1F ~,1F,~,1F\" fill=\"~A\"/>~%" x (- y 4) (+ x 4) y x (+ y 4) (- x 4) y colour))))

(defun write-peer-diagram (path title measure points)
  "Write to PATH an SVG diagram of POINTS (one scene, every engine): log10 of the error against
log10 of the wall milliseconds per simulated second, a curve per engine setting through its
step rates, each engine a colour and a marker, and a legend. Errors below 1e-9 are drawn at
1e-9. #P33R5X"
  (let* ((x0 72) (x1 470) (y0 34) (y1 384) (width 760) (height 440)
         (lx (lambda (p) (log (max 1d-3 (getf p :ms)) 10d0)))
         (ly (lambda (p) (log (max 1d-9 (getf p :error)) 10d0)))
         (xmin (floor (reduce #'min points :key lx))) (xmax (max (1+ xmin) (ceiling (reduce #'max points :key lx))))
         (ymin (floor (reduce #'min points :key ly))) (ymax (max (1+ ymin) (ceiling (reduce #'max points :key ly))))
         (curves (remove-duplicates (mapcar (lambda (p) (list (getf p :engine) (getf p :curve))) points) :test #'equal :from-end t)))
    (flet ((sx (v) (+ x0 (* (- x1 x0) (/ (- v xmin) (- xmax xmin)))))
           (sy (v) (- y1 (* (- y1 y0) (/ (- v ymin) (- ymax ymin))))))
      (with-open-file (out path :direction :output :if-exists :supersede)
        (write-log-axes out width height x0 y0 x1 y1 xmin xmax ymin ymax title measure)
        (loop for (engine label) in curves
              for row from 0
              for style = (cdr (assoc engine +engine-styles+))
              for index = (position label (remove engine curves :key #'first :test-not #'eq) :key #'second :test #'string=)
              for dash = (nth (mod index (length +curve-dashes+)) +curve-dashes+)
              for curve = (sort (remove-if-not (lambda (p) (and (eq (getf p :engine) engine) (string= (getf p :curve) label))) points)
                                #'< :key (lambda (p) (getf p :hz)))
              do (format out "<polyline fill=\"none\" stroke=\"~A\" stroke-width=\"1.5\" stroke-dasharray=\"~A\" points=\"~{~,1F,~,1F~^ ~}\"/>~%"
                         (first style) dash (loop for p in curve collect (sx (funcall lx p)) collect (sy (funcall ly p))))
                 (dolist (p curve) (svg-marker out (second style) (sx (funcall lx p)) (sy (funcall ly p)) (first style)))
                 (let ((y (+ y0 8 (* 15 row))))
                   (format out "<line x1=\"~D\" y1=\"~D\" x2=\"~D\" y2=\"~D\" stroke=\"~A\" stroke-width=\"1.5\" stroke-dasharray=\"~A\"/>~%"
                           (+ x1 14) y (+ x1 44) y (first style) dash)
                   (svg-marker out (second style) (+ x1 29) y (first style))
                   (format out "<text x=\"~D\" y=\"~D\">~A</text>~%" (+ x1 50) (+ y 4) label)))
        (format out "<text x=\"~D\" y=\"~D\" font-size=\"10\" fill=\"#555\">points: 30, 60, 120, 240 Hz</text>~%" (+ x1 14) (- y1 4))
        (format out "</svg>~%")))
    path))

(defparameter +engine-names+ '((:luv . "this engine") (:bullet . "Bullet") (:ode . "ODE") (:box3d . "Box3D"))
  "How the tables name each engine. #P33R5X")

(defun peer-point-label (p)
  "A point as the tables name it: its curve and rate. #P33R5X"
  (format nil "~A at ~D Hz" (getf p :curve) (getf p :hz)))

(defparameter +accuracy-levels+ '(10 1 1/10 1/100)
  "The accuracy levels of the table, as multiples of a scene's tolerance. #P33R5X")

(defun cheapest-within (points level)
  "The cheapest of POINTS whose error is within LEVEL, or NIL. #P33R5X"
  (let ((within (remove-if-not (lambda (p) (<= (getf p :error) level)) points)))
    (and within (reduce (lambda (a b) (if (<= (getf a :ms) (getf b :ms)) a b)) within))))

(defparameter +peer-why+
  '((free-fall . "Free fall's error is the substep's alone, g t h/2 in every engine, so the cheapest step wins, and this engine's fixed cost a step and a substep, for one ball, is several times a peer's.")
    (bounce . "One ball on a floor: the peers reach the same apexes within the tolerance, and their step for one ball costs less than this engine's.")
    (slide-to-roll . "ODE's contact solve follows the friction law as closely as this engine's, for less a step with one ball.")
    (seams . "Bullet and ODE meet the floor as one flat box, with no seams to cross, and their step for one ball costs less; this engine's error stays far inside the tolerance.")
    (resting . "Every engine rests the ball well within the tolerance, so the cheapest step wins.")
    (head-on . "Every engine keeps momentum and the restitution law here, so the cheapest step wins.")
    (shaft-stack . "ODE's solve and Box3D's soft step hold the stack too, each for less a step than this engine's.")
    (pile . "Where a peer's pile settles closer to the reference, it pays several times this engine's time for it.")
    (bounce-series . "A peer's rebound ratios off e^2 at low restitution or height count only within ten times the tolerance.")
    (cradle . "Within ten times the tolerance a row that passes only part of its momentum counts, and a peer's cheaper step wins; within the tolerance only this engine passes it on.")
    (struck-row . "Within ten times the tolerance a row that passes only part of its momentum counts, and a peer's cheaper step wins; within the tolerance only this engine passes it on.")
    (oblique-pair . "Within ten degrees a peer's impulse counts, from a contact found a step late and a little deep; within the tolerance only this engine's speculative contact, which takes the normal at the touch.")
    (edge-drop . "Within ten degrees a peer's impulse counts, from a contact found a step late and deep in the cell; within the tolerance only this engine, whose speculative contact takes the normal at the touch.")
    (corner-drop . "Within ten degrees a peer's impulse counts, from a contact found a step late and deep in the cell; within the tolerance only this engine, whose speculative contact takes the normal at the touch.")
    (rolling-resistance . "ODE's solve meets the rolling limit exactly for less a step; this engine's soft contact lets the speed stray a little more, still far within the tolerance."))
  "Why this engine is not the cheapest at a level where another engine is: one sentence per scene,
printed only when it applies. #P33R5X")

(defun print-peer-table (points stream)
  "Print, per scene, the engine with the cheapest point within each accuracy level of
+accuracy-levels+ times the scene's tolerance (that point is on the scene's joint Pareto front),
each engine's error at its defaults, and the engines with a point on the joint front. #P33R5X"
  (format stream "~&| scene | tolerance |~{ within ~A x |~} defaults: this / Bullet / ODE / Box3D | on the front |~%" +accuracy-levels+)
  (format stream "~&|-------+-----------+~{~*-----+~}------+------|~%" +accuracy-levels+)
  (loop for (scene nil nil tolerance) in *accuracy-scenes*
        for mine = (remove scene points :key (lambda (p) (getf p :scene)) :test-not #'eq)
        when mine
          do (flet ((default (engine curve hz)
                      (let ((p (find-if (lambda (p) (and (eq (getf p :engine) engine) (string= (getf p :curve) curve) (= (getf p :hz) hz))) mine)))
                        (if p (format nil "~,1,,,,,'eE" (getf p :error)) "-"))))
               (format stream "~&| ~(~A~) | ~A |~{ ~A |~} ~A / ~A / ~A / ~A | ~{~A~^, ~} |~%"
                       scene tolerance
                       (loop for level in +accuracy-levels+
                             collect (let ((p (cheapest-within mine (* level tolerance))))
                                       (if p (format nil "~A (~,2F ms/s)" (cdr (assoc (getf p :engine) +engine-names+)) (getf p :ms)) "none")))
                       (default :luv "this engine, 4 substeps" 60) (default :bullet "Bullet defaults (margin 0.04)" 60)
                       (default :ode "ODE quick step, 20 iterations" 60) (default :box3d "Box3D, 4 substeps" 60)
                       (mapcar (lambda (e) (cdr (assoc e +engine-names+)))
                               (remove-duplicates (mapcar (lambda (p) (getf p :engine)) (pareto-front mine)) :from-end t))))))

(defun print-peer-notes (points stream)
  "Print, per scene, each engine's best (the cheapest within the tolerance, else the most
accurate, with its setting) and, where this engine is not the cheapest at a level another
engine reaches, the sentence of +peer-why+. #P33R5X"
  (loop for (scene nil measure tolerance) in *accuracy-scenes*
        for mine = (remove scene points :key (lambda (p) (getf p :scene)) :test-not #'eq)
        when mine
          do (format stream "~&- ~(~A~) (~A), each engine's best:" scene measure)
             (loop for (engine) in +engine-names+
                   for own = (remove engine mine :key (lambda (p) (getf p :engine)) :test-not #'eq)
                   when own
                     do (let ((best (good-enough own tolerance)))
                          (format stream " ~A, ~,2,,,,,'eE at ~,2F ms/s~:[ (none within the tolerance)~;~];" (peer-point-label best)
                                  (getf best :error) (getf best :ms) (<= (getf best :error) tolerance))))
             (let ((behind (loop for level in +accuracy-levels+
                                 for p = (cheapest-within mine (* level tolerance))
                                 thereis (and p (not (eq (getf p :engine) :luv))))))
               (when (and behind (plusp (length (or (cdr (assoc scene +peer-why+)) ""))))
                 (format stream "~%  ~A" (cdr (assoc scene +peer-why+)))))
             (unless (every (lambda (p) (getf p :repeated)) mine)
               (format stream "~%  (some point ended differently in its two runs)"))
             (terpri stream)))

(defun run-peer-report (&key (directory (peer-file "report/")) (stream *standard-output*))
  "Write the scene file report/peers/scenes.txt, run the sweep of every engine on it, and write
report/peers-table.org (the table and the notes) and a diagram per scene,
report/wp-peers-SCENE.svg. #P33R5X"
  (let* ((scenes-file (merge-pathnames "peers/scenes.txt" directory)))
    (ensure-directories-exist scenes-file)
    (write-peer-scenes scenes-file)
    (let ((points (run-peer-sweep :scenes-file scenes-file :stream stream)))
      (with-open-file (out (merge-pathnames "peers/points.sexp" directory) :direction :output :if-exists :supersede)
        (with-standard-io-syntax (let ((*package* (find-package '#:luv-physics))) (prin1 points out))))
      (write-peer-figures points directory))))

(defun write-peer-figures (points directory)
  "Write the table and notes of POINTS to DIRECTORY's peers-table.org and a diagram per scene,
wp-peers-SCENE.svg. #P33R5X"
  (progn
      (with-open-file (out (merge-pathnames "peers-table.org" directory) :direction :output :if-exists :supersede)
        (format out "#+caption: the cheapest engine within each multiple of the tolerance, ms per simulated second; ~A; load ~A~%"
                (cpu-model-name) (load-average))
        (print-peer-table points out)
        (terpri out)
        (print-peer-notes points out))
      (dolist (entry *accuracy-scenes*)
        (let ((mine (remove (first entry) points :key (lambda (p) (getf p :scene)) :test-not #'eq)))
          (when mine
            (write-peer-diagram (merge-pathnames (format nil "wp-peers-~(~A~).svg" (first entry)) directory)
                                (format nil "~(~A~): error against run time, engine beside engine" (first entry)) (third entry)
                                mine))))
      points))
;; Error against run time, engine beside engine:8 ends here

;; [[file:../physics.org::#G4WXCJ][Watching a run: the recorder:1]]
(defconstant +recorded-contacts+ 64
  "The most touching contacts a recorded frame keeps, the first in the world's rows. #G4WXCJ")

(defstruct (physics-recording (:constructor %make-physics-recording (terrain every &optional bounds)))
  "A run as it was stepped, one frame every EVERY steps: each body's centre (XYZ, three floats),
RADIUS, STYLE (its kind's number times two, plus one for a sleeper), HANDLE and VELOCITY (three
floats); each frame's first body, body count and figures (FRAMES); each frame's first contact in
CONTACTS (CONTACT-STARTS), six floats a contact, point and normal; each frame's first joint in
JOINTS (JOINT-STARTS), six floats a joint, its two anchors' points; the boxes posted for each
recorded step (BOXES, a list of frame and centre and half extents); each box body's place among
the bodies (BOX-INDEX) and its orientation and half-extents (BOX-SHAPE, seven floats a box: W X Y Z,
then HX HY HZ); the world's TERRAIN, to draw its cells; and BOUNDS, NIL or the corners (x0 y0 z0
x1 y1 z1) of the terrain to draw. #G4WXCJ"
  (terrain nil)
  (bounds nil)
  (every 1 :type (integer 1 3600))
  (steps 0 :type fixnum)
  (xyz (make-array 4096 :element-type 'single-float :adjustable t :fill-pointer 0))
  (radius (make-array 1024 :element-type 'single-float :adjustable t :fill-pointer 0))
  (style (make-array 1024 :element-type '(unsigned-byte 8) :adjustable t :fill-pointer 0))
  (handle (make-array 1024 :element-type 'fixnum :adjustable t :fill-pointer 0))
  (velocity (make-array 4096 :element-type 'single-float :adjustable t :fill-pointer 0))
  (contacts (make-array 1024 :element-type 'single-float :adjustable t :fill-pointer 0))
  (contact-starts (make-array 64 :element-type 'fixnum :adjustable t :fill-pointer 0))
  (joints (make-array 0 :element-type 'single-float :adjustable t :fill-pointer 0))
  (joint-starts (make-array 64 :element-type 'fixnum :adjustable t :fill-pointer 0))
  (frames (make-array 64 :adjustable t :fill-pointer 0))
  (boxes '())
  (box-index (make-array 0 :element-type 'fixnum :adjustable t :fill-pointer 0))
  (box-shape (make-array 0 :element-type 'single-float :adjustable t :fill-pointer 0)))

(defun record-box-body (recording world buffer row index)
  "Append to RECORDING the box body at ROW of BUFFER, of WORLD, as the body INDEX of its bodies:
its place, and its orientation and half-extents. #G4WXCJ"
  (let ((set (physics-world-box-bodies world))
        (slot (handle-index (aref (body-columns-handle buffer) row)))
        (shape (physics-recording-box-shape recording)))
    (vector-push-extend index (physics-recording-box-index recording))
    (dolist (v (list (aref (body-columns-qw buffer) row) (aref (body-columns-qx buffer) row)
                     (aref (body-columns-qy buffer) row) (aref (body-columns-qz buffer) row)
                     (aref (box-set-hx set) slot) (aref (box-set-hy set) slot) (aref (box-set-hz set) slot)))
      (vector-push-extend v shape))))

(defun record-physics-frame (recording world)
  "Append WORLD's present state to RECORDING as one frame: every body, awake ones first (a box
body's orientation and extents beside it, record-box-body), the boxes posted for the step, the first +recorded-contacts+ touching contacts, every joint's two anchor
points ([[#J0STOR]]), and the frame's figures, a
vector of the first body, the body count, the awake and sleeping counts, the contacts, the step's
milliseconds and the simulated seconds. #G4WXCJ"
  (let* ((xyz (physics-recording-xyz recording))
         (velocity (physics-recording-velocity recording))
         (first (floor (fill-pointer xyz) 3))
         (frame (fill-pointer (physics-recording-frames recording))))
    (flet ((take (buffer asleep)
             (dotimes (row (body-columns-length buffer))
               (when (logtest (aref (body-columns-flags buffer) row) +flag-box-shape+)
                 (record-box-body recording world buffer row (floor (fill-pointer xyz) 3)))
               (vector-push-extend (aref (body-columns-x buffer) row) xyz)
               (vector-push-extend (aref (body-columns-y buffer) row) xyz)
               (vector-push-extend (aref (body-columns-z buffer) row) xyz)
               (vector-push-extend (aref (body-columns-vx buffer) row) velocity)
               (vector-push-extend (aref (body-columns-vy buffer) row) velocity)
               (vector-push-extend (aref (body-columns-vz buffer) row) velocity)
               (vector-push-extend (aref (body-columns-handle buffer) row) (physics-recording-handle recording))
               (vector-push-extend (aref (body-columns-radius buffer) row) (physics-recording-radius recording))
               (vector-push-extend (+ (* 2 (min 127 (max 0 (aref (body-columns-kind buffer) row))))
                                      (if asleep 1 0))
                                   (physics-recording-style recording)))))
      (take (physics-world-awake world) nil)
      (take (physics-world-sleeping world) t))
    (let* ((out (physics-recording-contacts recording))
           (c (physics-world-contacts world))
           (geometry (contact-columns-geometry c)))
      (vector-push-extend (floor (fill-pointer out) 6) (physics-recording-contact-starts recording))
      (loop with kept = 0
            for row below (contact-columns-length c)
            while (< kept +recorded-contacts+)
            when (= 1 (aref (contact-columns-touching c) row))
              do (incf kept)
                 (dolist (v (list (contact@ geometry row px) (contact@ geometry row py) (contact@ geometry row pz)
                                  (contact@ geometry row nx) (contact@ geometry row ny) (contact@ geometry row nz)))
                   (vector-push-extend v out))))
    (let ((out (physics-recording-joints recording)))
      (vector-push-extend (floor (fill-pointer out) 6) (physics-recording-joint-starts recording))
      (dotimes (row (physics-world-joint-count world))
        (dolist (v (multiple-value-list (joint-anchor-points world row)))
          (vector-push-extend v out))))
    (let ((boxes (physics-world-boxes world)))
      (dotimes (row (box-columns-length boxes))
        (flet ((middle (lo hi) (* 0.5 (+ (aref lo row) (aref hi row))))
               (half (lo hi) (* 0.5 (- (aref hi row) (aref lo row)))))
          (push (list frame
                      (middle (box-columns-min-x boxes) (box-columns-max-x boxes))
                      (middle (box-columns-min-y boxes) (box-columns-max-y boxes))
                      (middle (box-columns-min-z boxes) (box-columns-max-z boxes))
                      (half (box-columns-min-x boxes) (box-columns-max-x boxes))
                      (half (box-columns-min-y boxes) (box-columns-max-y boxes))
                      (half (box-columns-min-z boxes) (box-columns-max-z boxes)))
                (physics-recording-boxes recording)))))
    (vector-push-extend
     (vector first (- (floor (fill-pointer xyz) 3) first)
             (physics-world-awake-count world) (physics-world-sleeping-count world)
             (if (zerop (physics-world-step-count world)) 0 (physics-world-last-step-contact-count world))
             (if (zerop (physics-world-step-count world))
                 0d0
                 (* 1000 (physics-world-last-step-real-seconds world)))
             (* (physics-world-step-count world) (physics-world-step-seconds world)))
     (physics-recording-frames recording))
    recording))

(defun check-recording-bounds (bounds)
  "BOUNDS when it is NIL or six reals X0 Y0 Z0 X1 Y1 Z1 with each low corner below its high one,
as single-floats; else an invalid-physics-parameter error naming :bounds. #G4WXCJ"
  (cond ((null bounds) nil)
        ((and (listp bounds) (= 6 (length bounds)) (every #'realp bounds)
              (< (first bounds) (fourth bounds)) (< (second bounds) (fifth bounds))
              (< (third bounds) (sixth bounds)))
         (mapcar (lambda (v) (float v 1.0)) bounds))
        (t (error 'invalid-physics-parameter :name :bounds :value bounds
                                             :expected "NIL or a list (x0 y0 z0 x1 y1 z1) with x0 < x1, y0 < y1, z0 < z1"))))

(defun start-physics-recording (world &key (every 1) bounds)
  "Record WORLD from now on: a frame of its present state, then a frame after every EVERY-th
step, through its step hook (which must be free). BOUNDS, when given, is the box (x0 y0 z0 x1 y1
z1) whose terrain the viewer draws. Return the recording. #G4WXCJ"
  (check-world world 'start-physics-recording)
  (check-count :every every 3600)
  (setf bounds (check-recording-bounds bounds))
  (when (physics-world-step-hook world)
    (error 'invalid-physics-parameter :world world :name :step-hook
                                      :value (physics-world-step-hook world)
                                      :expected "NIL: a world is recorded by one recording at a time"))
  (let ((recording (%make-physics-recording (physics-world-terrain world) every bounds)))
    (record-physics-frame recording world)
    (setf (physics-world-step-hook world)
          (lambda (world)
            (when (zerop (mod (incf (physics-recording-steps recording)) (physics-recording-every recording)))
              (record-physics-frame recording world))))
    recording))

(defun stop-physics-recording (world)
  "Stop recording WORLD: its step hook is NIL again. Return WORLD. #G4WXCJ"
  (check-world world 'stop-physics-recording)
  (setf (physics-world-step-hook world) nil)
  world)

(defun physics-recording-frame-count (recording)
  "The number of frames RECORDING holds. #G4WXCJ"
  (fill-pointer (physics-recording-frames recording)))
;; Watching a run: the recorder:1 ends here

;; [[file:../physics.org::#3X6XN8][The standard scenes:1]]
(define-physics-scene :pile
    "1000 balls with rolling resistance, left until the whole pile sleeps #3X6XN8"
  (:terrain () (make-basin-terrain))
  (:world :sleep t :kernels :auto)
  (:bodies 1000 :spawn basin-spawn-point :radius 0.25 :mass 1.0 :friction 0.6 :rolling-resistance 0.05)
  (:seconds 12)
  (:pictures 1 4 12)
  (:features :terrain :body-contacts :friction :rolling-resistance :sleep))

(define-physics-scene :fountain
    "a fountain in the basin's floor: two water drops a step #3X6XN8"
  (:terrain () (make-basin-terrain))
  (:world :sleep t :kernels :auto)
  (:springs (make-basin-fountain))
  (:seconds 6)
  (:pictures 0.6 2 6)
  (:features :terrain :friction :sleep :mortal))

(define-physics-scene :lava
    "a lava spring in the basin's floor: a gobbet every fourth step, each living 4 s #3X6XN8"
  (:terrain () (make-basin-terrain))
  (:world :sleep t :kernels :auto)
  (:springs (make-lava-spring 4 -1 4))
  (:seconds 8)
  (:pictures 1 4 8)
  (:features :terrain :body-contacts :friction :restitution :sleep :mortal))

(define-physics-scene :player
    "the walker going round a square through two layers of balls #3X6XN8"
  (:terrain () (make-basin-terrain))
  (:world :sleep t :kernels :auto)
  (:bodies 392 :spawn basin-spawn-point :radius 0.25 :mass 1.0 :friction 0.6)
  (:player (1d0 0d0 1d0) player-scene-input)
  (:seconds 8)
  (:pictures 1 3.5 7)
  (:features :terrain :body-contacts :boxes :friction :sleep))

(defun player-scene-input (step)
  "The walker's input at STEP of the player scene: still for the first second, then round a
square, 1.5 s a side, as two values MOVE-X MOVE-Z. #3X6XN8"
  (if (< step 60)
      (values 0d0 0d0)
      (ecase (mod (floor (- step 60) 90) 4)
        (0 (values 1d0 0d0)) (1 (values 0d0 1d0)) (2 (values -1d0 0d0)) (3 (values 0d0 -1d0)))))
;; The standard scenes:1 ends here

;; [[file:../physics.org::#J0SCNE][Scenes of joints:1]]
(defun joint-scene-terrain ()
  "The terrain of the joints' scenes: resident air in [-8,8) x [0,12) x [-8,8) over a floor one
cell thick, y in [-1,0). #J0SCNE"
  (let ((terrain (make-voxel-terrain)))
    (fill-terrain terrain -8 0 -8 8 12 8 nil)
    (fill-terrain terrain -8 -1 -8 8 0 8 t)
    terrain))

(defun chain-point (i)
  "The centre of ball I of the chain scene: the twelve lie 0.5 m apart along x from the fixed
point (0, 8, 0). #J0SCNE"
  (values (* 0.5 (1+ i)) 8.0 0.0))

(defun join-chain (world balls)
  "Hang BALLS, the chain's in order, from the fixed point (0, 8, 0) by a rope to the first one's
centre, and join each centre to the next by a stiff distance joint of the 0.5 m between them. #J0SCNE"
  (add-physics-joint world :distance (first balls) nil :anchor-b '(0 8 0) :rope t)
  (loop for (p q) on balls while q do (add-physics-joint world :distance p q)))

(define-physics-scene :chain
    "a chain of twelve balls on distance joints, hung by a rope and let go sideways, over a floor #J0SCNE"
  (:terrain () (joint-scene-terrain))
  (:world :sleep t :kernels :auto)
  (:bodies 12 :spawn chain-point :radius 0.2 :mass 1.0 :friction 0.3)
  (:bodies 1 :spawn (lambda (i) (declare (ignore i)) (values 2.0 0.2 0.0)) :radius 0.3 :friction 0.3)
  (:joints (world bodies) (join-chain world (subseq bodies 0 12)))
  (:seconds 10)
  (:features :terrain :friction :sleep :joints))

(define-physics-scene :cradle
    "Newton's cradle on strings: five touching balls on two strings each, the first let go from 30 degrees #J0SCNE"
  (:terrain () (joint-scene-terrain))
  (:world :sleep t :kernels :auto)
  (:bodies 5 :spawn cradle-point :radius 0.25 :mass 1.0 :friction 0.0 :restitution 1.0)
  (:joints (world bodies) (hang-cradle world bodies))
  (:seconds 6)
  (:features :body-contacts :restitution :sleep :joints))
;; Scenes of joints:1 ends here

;; [[file:../physics.org::#BXSC3N][Scenes of boxes:1]]
(defun tower-block-point (i)
  "The centre of block I of the tower scene: on the floor's top at y = 0, each block a metre above
the one below and 0.15 m further along x, the lowest at x = -3. #BXSC3N"
  (values (+ -3.0 (* 0.15 i)) (+ 0.5 i) 0.5))

(define-physics-scene :tower
    "a leaning tower of eight unit blocks on a floor, past its balance: it topples #BXSC3N"
  (:terrain () (joint-scene-terrain))
  (:world :sleep t :kernels :auto)
  (:bodies 8 :spawn tower-block-point :half-extents '(0.5 0.5 0.5) :mass 1.0 :friction 0.6)
  (:seconds 6)
  (:pictures 0.5 1.5 4)
  (:features :friction :sleep :box-bodies))

(defun crate-point (i)
  "The centre of crate I of the crates scene: four on the floor along x at z = 0.5, from x = -4,
and a fifth on the second. #BXSC3N"
  (if (= i 4)
      (values -2.0 1.2 0.5)
      (values (nth i '(-4.0 -2.0 0.0 2.0)) 0.4 0.5)))

(defun crates-scene-input (step)
  "The walker's input at STEP of the crates scene: still for a quarter second, then along +x at
half its speed until 5.5 s, then still, as two values MOVE-X MOVE-Z. #BXSC3N"
  (if (< 15 step 330) (values 0.5d0 0d0) (values 0d0 0d0)))

(defun crates-scene-terrain ()
  "The joints' scenes' floor (joint-scene-terrain) with a wall of cells 3 m high from x = 6 to
its end at 8. #BXSC3N"
  (let ((terrain (joint-scene-terrain)))
    (fill-terrain terrain 6 0 -8 8 3 8 t)
    terrain))

(define-physics-scene :crates
    "the walker pushing a row of crates along the floor until they jam against a wall #BXSC3N"
  (:terrain () (crates-scene-terrain))
  (:world :sleep t :kernels :auto)
  (:bodies 5 :spawn crate-point :half-extents '(0.4 0.4 0.4) :mass 10.0 :friction 0.6)
  (:player (-6d0 0d0 0.5d0) crates-scene-input)
  (:seconds 7)
  (:pictures 1 3.5 6)
  (:features :boxes :friction :sleep :box-bodies))
;; Scenes of boxes:1 ends here

;; [[file:../physics.org::#RH7T05][A viewer for the browser:1]]
(defun write-base64 (octets stream)
  "Write the vector of octets OCTETS to STREAM in base64 (RFC 4648, padded with =). #RH7T05"
  (let ((alphabet "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/")
        (n (length octets)))
    (loop for i from 0 below n by 3
          do (let ((word (logior (ash (aref octets i) 16)
                                 (if (< (+ i 1) n) (ash (aref octets (+ i 1)) 8) 0)
                                 (if (< (+ i 2) n) (aref octets (+ i 2)) 0))))
               (write-char (char alphabet (ldb (byte 6 18) word)) stream)
               (write-char (char alphabet (ldb (byte 6 12) word)) stream)
               (write-char (if (< (+ i 1) n) (char alphabet (ldb (byte 6 6) word)) #\=) stream)
               (write-char (if (< (+ i 2) n) (char alphabet (ldb (byte 6 0) word)) #\=) stream)))))

(defun recording-bounds (recording &key (pad 0.5))
  "The box of every centre RECORDING holds, grown by PAD on every side, as two lists of three
single-floats, LO and HI. #RH7T05"
  (let ((xyz (physics-recording-xyz recording))
        (lo (list most-positive-single-float most-positive-single-float most-positive-single-float))
        (hi (list most-negative-single-float most-negative-single-float most-negative-single-float)))
    (loop for i from 0 below (fill-pointer xyz)
          do (let ((axis (mod i 3)))
               (setf (nth axis lo) (min (nth axis lo) (aref xyz i))
                     (nth axis hi) (max (nth axis hi) (aref xyz i)))))
    (if (zerop (fill-pointer xyz))
        (values (list 0.0 0.0 0.0) (list 1.0 1.0 1.0))
        (values (mapcar (lambda (v) (- v pad)) lo) (mapcar (lambda (v) (+ v pad)) hi)))))

(defun recording-cell-box (recording &optional (bounds (physics-recording-bounds recording)))
  "The box whose terrain the viewer draws for RECORDING, as two lists of three single-floats LO
and HI: BOUNDS (x0 y0 z0 x1 y1 z1) when given, else the box of its centres grown by a cell on
every side. #RH7T05"
  (if bounds
      (values (subseq bounds 0 3) (subseq bounds 3 6))
      (recording-bounds recording :pad 1.0)))

(defun recording-cells (recording &optional (bounds (physics-recording-bounds recording)))
  "The resident solid cells of RECORDING's terrain with an air neighbour, inside BOUNDS (x0 y0 z0
x1 y1 z1) when given, else the box of its centres grown by a cell on every side: a list of X Y Z,
flat. #RH7T05"
  (let ((terrain (physics-recording-terrain recording)) (cells '()))
    (when (and terrain (or bounds (plusp (fill-pointer (physics-recording-xyz recording)))))
      (multiple-value-bind (lo hi) (recording-cell-box recording bounds)
        (flet ((air-p (x y z) (and (terrain-resident-p terrain x y z) (not (terrain-solid-p terrain x y z)))))
          (loop for x from (floor (first lo)) below (ceiling (first hi))
                do (loop for y from (floor (second lo)) below (ceiling (second hi))
                         do (loop for z from (floor (third lo)) below (ceiling (third hi))
                                  when (and (terrain-resident-p terrain x y z) (terrain-solid-p terrain x y z)
                                            (or (air-p (1+ x) y z) (air-p (1- x) y z) (air-p x (1+ y) z)
                                                (air-p x (1- y) z) (air-p x y (1+ z)) (air-p x y (1- z))))
                                    do (push z cells) (push y cells) (push x cells)))))))
    cells))

(defun recording-palette (recording)
  "The distinct (radius kind sleeper) triples of RECORDING's bodies, radius to 0.1 mm, as a vector,
and a vector of each body's index into it; at most 256 triples. #RH7T05"
  (let* ((radius (physics-recording-radius recording)) (style (physics-recording-style recording))
         (table (make-hash-table :test 'equal)) (palette (make-array 0 :adjustable t :fill-pointer t))
         (indices (make-array (length style) :element-type '(unsigned-byte 8))))
    (dotimes (i (length style))
      (let ((key (list (/ (round (aref radius i) 1e-4) 1d4) (ash (aref style i) -1) (logand (aref style i) 1))))
        (setf (aref indices i)
              (or (gethash key table)
                  (progn (when (= (length palette) 256)
                           (error 'invalid-physics-parameter :name :recording :value recording
                                                             :expected "at most 256 distinct radius, kind and sleep triples"))
                         (vector-push-extend key palette)
                         (setf (gethash key table) (1- (length palette))))))))
    (values palette indices)))

(defun recording-quanta (recording lo hi)
  "RECORDING's centres as octets: three little-endian unsigned 16-bit numbers a body, each
coordinate spread over LO..HI, computed in double-floats. #RH7T05"
  (let* ((lo (mapcar (lambda (v) (float v 1d0)) lo)) (hi (mapcar (lambda (v) (float v 1d0)) hi))
         (xyz (physics-recording-xyz recording))
         (octets (make-array (* 2 (fill-pointer xyz)) :element-type '(unsigned-byte 8))))
    (dotimes (i (fill-pointer xyz) octets)
      (let* ((axis (mod i 3))
             (q (max 0 (min 65535 (round (* 65535 (/ (- (float (aref xyz i) 1d0) (nth axis lo))
                                                     (- (nth axis hi) (nth axis lo)))))))))
        (setf (aref octets (* 2 i)) (ldb (byte 8 0) q)
              (aref octets (1+ (* 2 i))) (ldb (byte 8 8) q))))))

(defun recording-handle-octets (recording)
  "RECORDING's handles as octets, their low 48 bits in six little-endian bytes a body, and the
bits above, which the handles of one world share (its tag's high bits). #RH7T05"
  (let* ((handles (physics-recording-handle recording))
         (octets (make-array (* 6 (fill-pointer handles)) :element-type '(unsigned-byte 8))))
    (dotimes (i (fill-pointer handles) octets)
      (dotimes (b 6)
        (setf (aref octets (+ (* 6 i) b)) (ldb (byte 8 (* 8 b)) (aref handles i)))))
    (values octets (if (plusp (length handles)) (ash (aref handles 0) -48) 0))))

(defun recording-velocity-octets (recording)
  "RECORDING's velocities as octets, three little-endian signed 16-bit numbers a body over the
fastest component's range, and that range, m/s. #RH7T05"
  (let* ((v (physics-recording-velocity recording))
         (top (max 1e-3 (reduce #'max v :key #'abs :initial-value 0.0)))
         (octets (make-array (* 2 (fill-pointer v)) :element-type '(unsigned-byte 8))))
    (dotimes (i (fill-pointer v))
      (let ((q (ldb (byte 16 0) (max -32767 (min 32767 (round (* 32767 (/ (float (aref v i) 1d0) top))))))))
        (setf (aref octets (* 2 i)) (ldb (byte 8 0) q)
              (aref octets (1+ (* 2 i))) (ldb (byte 8 8) q))))
    (values octets top)))

(defun recording-box-bodies (recording)
  "RECORDING's box bodies as a list of lists, each the body's place among the recorded bodies and
its orientation W X Y Z and half-extents HX HY HZ. #RH7T05"
  (let ((shape (physics-recording-box-shape recording)))
    (loop for index across (physics-recording-box-index recording)
          for k from 0 by 7
          collect (cons index (coerce (subseq shape k (+ k 7)) 'list)))))

(defun write-recording-json (recording title stream &optional (bounds (physics-recording-bounds recording)))
  "Write RECORDING to STREAM as the JavaScript object the viewer reads, titled TITLE, its terrain
drawn within BOUNDS (recording-cells). #RH7T05"
  (multiple-value-bind (lo hi) (recording-bounds recording)
    (multiple-value-bind (palette indices) (recording-palette recording)
      (let ((frames (physics-recording-frames recording)))
        (format stream "{\"title\": ~S,~%\"frameSeconds\": ~,6F,~%\"lo\": [~{~,4F~^, ~}], \"hi\": [~{~,4F~^, ~}],~%"
                (remove-if (lambda (c) (find c "\"\\")) title)
                (if (> (length frames) 1)
                    (/ (- (aref (aref frames (1- (length frames))) 6) (aref (aref frames 0) 6))
                       (1- (length frames)))
                    (/ 1 60.0))
                lo hi)
        (format stream "\"kinds\": [\"body\"~{, \"~(~A~)\"~}],~%" (mapcar #'first *physics-body-kinds*))
        (format stream "\"palette\": [~{[~{~,4F, ~D, ~D~}]~^, ~}],~%" (coerce palette 'list))
        (format stream "\"frames\": [~%~{[~{~D, ~D, ~D, ~D, ~D, ~,4F, ~,4F~}]~^,~%~}],~%"
                (map 'list (lambda (f) (coerce f 'list)) frames))
        (format stream "\"boxes\": [~{[~{~D~@{, ~,4F~}~}]~^, ~}],~%" (reverse (physics-recording-boxes recording)))
        (format stream "\"boxBodies\": [~{[~{~D~@{, ~,5F~}~}]~^, ~}],~%" (recording-box-bodies recording))
        (format stream "\"cells\": [~{~D~^,~}],~%" (recording-cells recording bounds))
        (multiple-value-bind (cell-lo cell-hi) (recording-cell-box recording bounds)
          (format stream "\"cellLo\": [~{~,4F~^, ~}], \"cellHi\": [~{~,4F~^, ~}],~%" cell-lo cell-hi))
        (format stream "\"contactStarts\": [~{~D~^,~}],~%" (coerce (physics-recording-contact-starts recording) 'list))
        (format stream "\"contacts\": [~{~,3F~^,~}],~%" (coerce (physics-recording-contacts recording) 'list))
        (format stream "\"jointStarts\": [~{~D~^,~}],~%" (coerce (physics-recording-joint-starts recording) 'list))
        (format stream "\"joints\": [~{~,3F~^,~}],~%" (coerce (physics-recording-joints recording) 'list))
        (format stream "\"positions\": \"")
        (write-base64 (recording-quanta recording lo hi) stream)
        (format stream "\",~%\"styles\": \"")
        (write-base64 indices stream)
        (multiple-value-bind (octets high) (recording-handle-octets recording)
          (format stream "\",~%\"handleHigh\": ~D,~%\"handles\": \"" high)
          (write-base64 octets stream))
        (multiple-value-bind (octets top) (recording-velocity-octets recording)
          (format stream "\",~%\"speedRange\": ~,6F,~%\"velocities\": \"" top)
          (write-base64 octets stream))
        (format stream "\"}~%")))))

(defun write-physics-viewer (recording pathname &key (title "a recorded run")
                                                  (bounds (physics-recording-bounds recording))
                                                  (template (asdf:system-relative-pathname "luv-physics" "tools/viewer.html"))
                                                  (three "/usr/share/javascript/three/"))
  "Write RECORDING to PATHNAME as one HTML file that plays it back in 3D: TEMPLATE with its marker
lines replaced by three.js and its orbit controls from the directory THREE (Debian's libjs-three)
and by the recording, titled TITLE, its terrain drawn within BOUNDS (x0 y0 z0 x1 y1 z1; by
default the recording's, else near the bodies). Return PATHNAME. #RH7T05"
  (setf bounds (check-recording-bounds bounds))
  (let ((library (merge-pathnames "three.min.js" three))
        (orbit (merge-pathnames "examples/js/controls/OrbitControls.js" three)))
    (unless (and (probe-file library) (probe-file orbit))
      (error 'invalid-physics-parameter :name :three :value three
                                        :expected "a directory with three.min.js and examples/js/controls/OrbitControls.js (Debian: apt-get install libjs-three)"))
    (with-open-file (out pathname :direction :output :if-exists :supersede :external-format :utf-8)
      (with-open-file (in template :external-format :utf-8)
        (loop for line = (read-line in nil) while line
              do (let ((marker (string-trim " " line)))
                   (cond ((string= marker "//@include three") (write-string (read-file-text library) out))
                         ((string= marker "//@include orbit") (write-string (read-file-text orbit) out))
                         ((string= marker "//@include data") (write-recording-json recording title out bounds))
                         (t (write-line line out)))))))
    pathname))

(defun write-world-viewer (world pathname &key (steps 240) (every 2) bounds (title "a world"))
  "Record WORLD for STEPS steps, a frame every EVERY, and write the recording's viewer to
PATHNAME, its terrain drawn within BOUNDS (x0 y0 z0 x1 y1 z1) or near the bodies. The world is
left stepped and no longer recorded. Return PATHNAME and the recording. #RH7T05"
  (check-world world 'write-world-viewer)
  (unless (and (integerp steps) (<= 0 steps 1000000))
    (error 'invalid-physics-parameter :world world :name :steps :value steps
                                      :expected "an integer from 0 to 1000000"))
  (let ((recording (start-physics-recording world :every every :bounds bounds)))
    (unwind-protect (dotimes (i steps) (step-physics-world world))
      (stop-physics-recording world))
    (values (write-physics-viewer recording pathname :title title) recording)))
;; A viewer for the browser:1 ends here

;; [[file:../physics.org::#UFK5EA][Pictures of the scenes:1]]
(defun view-basis (azimuth elevation)
  "The unit vectors across the picture, up the picture and towards the viewer of an orthographic
view from AZIMUTH degrees round from +z about +y and ELEVATION degrees above the horizon, as
three lists. #UFK5EA"
  (let* ((a (* azimuth (/ pi 180))) (e (* elevation (/ pi 180)))
         (d (list (* (cos e) (sin a)) (sin e) (* (cos e) (cos a))))
         (across (let ((l (sqrt (+ (expt (third d) 2) (expt (first d) 2)))))
                   (list (/ (third d) l) 0 (/ (- (first d)) l))))
         (up (list (- (* (second d) (third across)) (* (third d) (second across)))
                   (- (* (third d) (first across)) (* (first d) (third across)))
                   (- (* (first d) (second across)) (* (second d) (first across))))))
    (values across up d)))

(defun shade (colour factor)
  "The #RRGGBB colour COLOUR (an integer) with each channel times FACTOR, as a string. #UFK5EA"
  (format nil "#~{~2,'0X~}"
          (loop for shift in '(16 8 0)
                collect (min 255 (round (* factor (ldb (byte 8 shift) colour)))))))

(defun frame-box-shapes (recording frame)
  "A table from the place of each box body of frame FRAME of RECORDING among its recorded bodies
to that box's orientation and half-extents, a list of seven numbers. #UFK5EA"
  (let* ((f (aref (physics-recording-frames recording) frame))
         (from (aref f 0)) (to (+ from (aref f 1)))
         (shape (physics-recording-box-shape recording))
         (table (make-hash-table)))
    (loop for index across (physics-recording-box-index recording)
          for k from 0 by 7
          when (and (<= from index) (< index to))
            do (setf (gethash index table) (coerce (subseq shape k (+ k 7)) 'list)))
    table))

(defun box-body-faces (x y z shape toward project)
  "The three faces of the box body centred at X Y Z of SHAPE (its orientation W X Y Z and
half-extents) that look towards TOWARD, the unit vector to the viewer: each a list of the depth of
its middle and its four corners, each projected by PROJECT, a function of three coordinates. #UFK5EA"
  (destructuring-bind (qw qx qy qz hx hy hz) shape
    (multiple-value-bind (r11 r12 r13 r21 r22 r23 r31 r32 r33)
        (box-axes (float qw 1.0) (float qx 1.0) (float qy 1.0) (float qz 1.0))
      (let ((axes (list (list r11 r21 r31) (list r12 r22 r32) (list r13 r23 r33)))
            (half (list hx hy hz)))
        (flet ((along (p axis amount) (mapcar (lambda (c a) (+ c (* amount a))) p (nth axis axes))))
          (loop for axis below 3
                for normal = (nth axis axes)
                for sign = (if (minusp (reduce #'+ (mapcar #'* normal toward))) -1 1)
                for middle = (along (list x y z) axis (* sign (nth axis half)))
                for a = (mod (1+ axis) 3) for b = (mod (+ 2 axis) 3)
                collect (cons (reduce #'+ (mapcar #'* middle toward))
                              (loop for (u v) in '((-1 -1) (1 -1) (1 1) (-1 1))
                                    collect (apply project (along (along middle a (* u (nth a half))) b (* v (nth b half))))))))))))

(defun scene-picture-items (recording frame cells across up toward)
  "What frame FRAME of RECORDING shows, as a list of (DEPTH KIND COLOUR . POINTS), deepest first:
the faces of CELLS (a flat list of X Y Z) that look towards the viewer and touch air (KIND :wall
for an upright face, else :face), discs (KIND :disc, POINTS the centre's projection and the
radius) or, for a box body, the three of its faces that look towards the viewer (:face), and
posted boxes' faces (:face), projected on ACROSS and UP. #UFK5EA"
  (let ((terrain (physics-recording-terrain recording)) (items '())
        (xyz (physics-recording-xyz recording)) (f (aref (physics-recording-frames recording) frame)))
    (labels ((dot (u x y z) (+ (* (first u) x) (* (second u) y) (* (third u) z)))
             (project (x y z) (list (dot across x y z) (- (dot up x y z))))
             (face (kind colour x y z axis sign sx sy sz)
               ;; the face of the box at X Y Z with sizes SX SY SZ whose normal is SIGN along AXIS
               (let* ((o (list x y z)) (s (list sx sy sz))
                      (a (mod (1+ axis) 3)) (b (mod (+ 2 axis) 3)) (corners '()))
                 (when (plusp sign) (incf (nth axis o) (nth axis s)))
                 (dolist (uv '((0 0) (1 0) (1 1) (0 1)))
                   (let ((p (copy-list o)))
                     (incf (nth a p) (* (first uv) (nth a s))) (incf (nth b p) (* (second uv) (nth b s)))
                     (push (apply #'project p) corners)))
                 (let ((m (copy-list o)))
                   (incf (nth a m) (* 0.5 (nth a s))) (incf (nth b m) (* 0.5 (nth b s)))
                   (push (list* (apply #'dot toward m) kind colour corners) items)))))
      (loop for (x y z) on cells by #'cdddr
            do (loop for axis below 3 for colour in '(#x8f937f #xbcc0a8 #xa3a791)
                     do (dolist (sign '(1 -1))
                          (let ((n (list 0 0 0)))
                            (setf (nth axis n) sign)
                            (when (and (plusp (* sign (nth axis toward)))
                                       (let ((nx (+ x (first n))) (ny (+ y (second n))) (nz (+ z (third n))))
                                         (and (terrain-resident-p terrain nx ny nz)
                                              (not (terrain-solid-p terrain nx ny nz)))))
                              (face (if (= axis 1) :face :wall) colour x y z axis sign 1 1 1))))))
      (loop with shapes = (frame-box-shapes recording frame)
            for i from (aref f 0) below (+ (aref f 0) (aref f 1))
            do (let* ((x (aref xyz (* 3 i))) (y (aref xyz (+ 1 (* 3 i)))) (z (aref xyz (+ 2 (* 3 i))))
                      (style (aref (physics-recording-style recording) i))
                      (colour (if (oddp style) #x6a7a98
                                  (nth (min 4 (ash style -1)) '(#xd9822b #xe0a030 #xc8c8d0 #x3f8fe0 #xe8401c))))
                      (shape (gethash i shapes)))
                 (if shape
                     (dolist (item (box-body-faces x y z shape toward #'project)) (push (list* (first item) :face colour (rest item)) items))
                     (push (list (dot toward x y z) :disc colour (project x y z)
                                 (aref (physics-recording-radius recording) i))
                           items))))
      (dolist (box (physics-recording-boxes recording))
        (destructuring-bind (at x y z hx hy hz) box
          (when (= at frame)
            (loop for axis below 3
                  do (face :face #x45b36b (- x hx) (- y hy) (- z hz) axis (if (plusp (nth axis toward)) 1 -1)
                           (* 2 hx) (* 2 hy) (* 2 hz)))))))
    (sort items #'< :key #'first)))

(defun frame-at (recording seconds)
  "The frame of RECORDING nearest to SECONDS of simulated time. #UFK5EA"
  (let ((frames (physics-recording-frames recording)))
    (loop with best = 0 for i below (length frames)
          when (< (abs (- (aref (aref frames i) 6) seconds)) (abs (- (aref (aref frames best) 6) seconds)))
            do (setf best i)
          finally (return best))))

(defun write-scene-picture (recording pathname moments &key (title "") (width 300) (height 250)
                                                         (azimuth 35) (elevation 40))
  "Write an SVG picture to PATHNAME: a panel of WIDTH x HEIGHT for each of MOMENTS (seconds) of
RECORDING, seen from AZIMUTH and ELEVATION, under TITLE. Return PATHNAME. #UFK5EA"
  (multiple-value-bind (across up toward) (view-basis azimuth elevation)
    (let* ((cells (recording-cells recording))
           (frames (mapcar (lambda (s) (frame-at recording s)) moments))
           (panels (mapcar (lambda (f) (scene-picture-items recording f cells across up toward)) frames))
           (xs '()) (ys '()) (depths '()))
      (dolist (items panels)
        (dolist (item items)
          (push (first item) depths)
          (if (eq (second item) :disc)
              (destructuring-bind ((x y) r) (cdddr item)
                (push (- x r) xs) (push (+ x r) xs) (push (- y r) ys) (push (+ y r) ys))
              (dolist (p (cdddr item)) (push (first p) xs) (push (second p) ys)))))
      ;; the drawing is fitted to what it shows, wherever that lies, and lit over the depths
      ;; it shows; a picture with nothing in it takes the unit square and a unit of depth
      (let* ((x0 (if xs (reduce #'min xs) 0)) (x1 (if xs (reduce #'max xs) 1))
             (y0 (if ys (reduce #'min ys) 0)) (y1 (if ys (reduce #'max ys) 1))
             (d0 (if depths (reduce #'min depths) 0)) (d1 (if depths (reduce #'max depths) 1))
             ;; at least a metre each way, so that a lone small ball is not blown up to the panel
             (top 22) (scale (min (/ (- width 10) (max 1 (- x1 x0))) (/ (- height top 6) (max 1 (- y1 y0))))))
        (flet ((px (x panel) (+ (* panel width) 5 (* scale (- x x0))))
               (py (y) (+ top (* scale (- y y0))))
               (light (depth) (+ 0.55 (* 0.45 (/ (- depth d0) (max 1e-6 (- d1 d0)))))))
          (with-open-file (out pathname :direction :output :if-exists :supersede)
            (format out "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"~D\" height=\"~D\" viewBox=\"0 0 ~:*~:*~D ~D\" font-family=\"sans-serif\" font-size=\"12\">~%"
                    (* width (length moments)) height)
            (format out "<style>circle { stroke: #333; stroke-width: 0.3 } polygon { stroke: #555; stroke-width: 0.3 }
 .wall { fill-opacity: 0.4 }</style>~%<rect width=\"100%\" height=\"100%\" fill=\"#fafaf7\"/>~%")
            (loop for items in panels for frame in frames for panel from 0
                  do (let ((f (aref (physics-recording-frames recording) frame)))
                       (format out "<text x=\"~D\" y=\"15\">~A~,1F s: ~D awake, ~D asleep</text>~%"
                               (+ 6 (* panel width)) (if (zerop panel) title "")
                               (aref f 6) (aref f 2) (aref f 3)))
                     (dolist (item items)
                       (destructuring-bind (depth kind colour &rest points) item
                         (if (eq kind :disc)
                             (destructuring-bind ((x y) r) points
                               (format out "<circle cx=\"~,1F\" cy=\"~,1F\" r=\"~,1F\" fill=\"~A\"/>~%"
                                       (px x panel) (py y) (* scale r) (shade colour (light depth))))
                             (format out "<polygon points=\"~{~{~,1F,~,1F~}~^ ~}\" fill=\"~A\"~:[~; class=\"wall\"~]/>~%"
                                     (mapcar (lambda (p) (list (px (first p) panel) (py (second p)))) points)
                                     (shade colour (light depth)) (eq kind :wall))))))
            (format out "</svg>~%")))))
    pathname))
;; Pictures of the scenes:1 ends here

;; [[file:../physics.org::#QB3NCH][What a query costs:1]]
(defun query-benchmark-inputs (count seed)
  "COUNT random queries for the basin, as an f32-column of seven floats each: a point of the
interior [0,8] x [0,6] x [0,8] and a direction, uniform over the sphere, and a spare. #QB3NCH"
  (let ((q (make-array (* 7 count) :element-type 'single-float))
        (state (sb-ext:seed-random-state seed)))
    (dotimes (i count q)
      (setf (aref q (* 7 i)) (random 8.0 state) (aref q (+ (* 7 i) 1)) (random 6.0 state)
            (aref q (+ (* 7 i) 2)) (random 8.0 state))
      (loop for (dx dy dz) = (list (- (random 2.0 state) 1.0) (- (random 2.0 state) 1.0) (- (random 2.0 state) 1.0))
            for l2 = (+ (* dx dx) (* dy dy) (* dz dz))
            when (< 0.01 l2 1.0)
              do (setf (aref q (+ (* 7 i) 3)) dx (aref q (+ (* 7 i) 4)) dy (aref q (+ (* 7 i) 5)) dz)
                 (return)))))

(defun time-queries (inputs count function)
  "Run FUNCTION on each of the COUNT queries of INPUTS, over and over until at least half a second
has passed; return the queries per second of wall time, per second of this process's processor
time, and the bytes consed per query. #QB3NCH"
  (declare (type f32-column inputs) (type function function))
  (funcall function inputs 0)
  (sb-ext:gc)
  (let ((start (clock-ns)) (cpu (get-internal-run-time)) (before (sb-ext:get-bytes-consed)) (done 0))
    (declare (type fixnum done))
    (loop do (dotimes (i count) (funcall function inputs (* 7 i)))
             (incf done count)
          until (> (- (clock-ns) start) 500000000))
    (values (/ done (* 1d-9 (- (clock-ns) start)))
            (/ done (/ (float (- (get-internal-run-time) cpu) 1d0) internal-time-units-per-second))
            (/ (float (- (sb-ext:get-bytes-consed) before) 1d0) done))))

(defun benchmark-query (world kind hit counter)
  "The query of KIND that measure-queries times in WORLD, as a function of an f32-column of
queries, as query-benchmark-inputs writes them, and the index of one's first float: a 10 m ray
(:ray) or a sphere cast of radius 0.25 m (:sphere) from its point along its direction, filling
HIT, or the bodies within 1 m of its point (:overlap), each passed to COUNTER. #QB3NCH"
  (declare (type function counter))
  (ecase kind
    (:ray (lambda (q i)
            (declare (type f32-column q) (type fixnum i))
            (physics-ray-cast world (aref q i) (aref q (+ i 1)) (aref q (+ i 2)) (aref q (+ i 3))
                              (aref q (+ i 4)) (aref q (+ i 5)) 10.0 :hit hit)))
    (:sphere (lambda (q i)
               (declare (type f32-column q) (type fixnum i))
               (physics-sphere-cast world (aref q i) (aref q (+ i 1)) (aref q (+ i 2)) 0.25
                                    (aref q (+ i 3)) (aref q (+ i 4)) (aref q (+ i 5)) 10.0 :hit hit)))
    (:overlap (lambda (q i)
                (declare (type f32-column q) (type fixnum i))
                (map-physics-bodies-in-sphere counter world (aref q i) (aref q (+ i 1)) (aref q (+ i 2)) 1.0)))))

(defun measure-queries (world)
  "Rays, sphere casts of radius 0.25 m and overlap queries (the bodies within 1 m of a point) per
second of wall time and of processor time in WORLD, and bytes consed per query, as a plist of
lists (wall cpu bytes). #QB3NCH"
  (let* ((count 20000) (inputs (query-benchmark-inputs count 2026)) (hit (make-physics-hit))
         (found 0) (counter (lambda (h) (declare (ignore h)) (incf found))))
    (declare (type fixnum found))
    (flet ((measure (kind)
             (multiple-value-list (time-queries inputs count (benchmark-query world kind hit counter)))))
      (list :rays (measure :ray) :spheres (measure :sphere) :overlaps (measure :overlap)))))

(defun settled-basin-world (count sleep)
  "The basin of COUNT balls after 300 steps, awake; with SLEEP, every ball of that pile then put
to sleep where it lies. #QB3NCH"
  (let ((world (make-basin-world count :kernels :auto :sleep sleep)))
    (dotimes (i 300) (step-physics-world world))
    (when sleep
      (loop for row from (1- (physics-world-awake-count world)) downto 0
            do (sleep-physics-body world row)))
    world))

(defun run-query-benchmark (&optional (stream *standard-output*))
  "Measure ray casts, sphere casts and overlap queries against the settled basin of 3000 and of
10000 balls, awake and asleep, and print an Org table to STREAM. #QB3NCH"
  (format stream "~&#+caption: queries against the basin pile, one thread: 10 m rays and sphere casts (radius 0.25 m) from random points of the interior [0,8] x [0,6] x [0,8] in random directions, and the bodies within 1 m of such a point; thousands of queries per second of wall time and per second of the process's processor time, and bytes consed per query; ~A; load ~A; ~A~%"
          (cpu-model-name) (load-average) (machine-probe))
  (format stream "| balls | state | awake | asleep | rays k/s | rays k/cpu-s | B/ray | casts k/s | casts k/cpu-s | B/cast | overlaps k/s | overlaps k/cpu-s | B/overlap |~%")
  (format stream "|-------+-------+-------+--------+----------+--------------+-------+-----------+---------------+--------+--------------+------------------+-----------|~%")
  (dolist (count '(3000 10000))
    (dolist (sleep '(nil t))
      (let* ((world (settled-basin-world count sleep))
             (m (measure-queries world)))
        (format stream "| ~D | ~A | ~D | ~D ~{~{| ~D | ~D | ~,1F ~}~}|~%"
                count (if sleep "asleep" "awake") (physics-world-awake-count world) (physics-world-sleeping-count world)
                (loop for key in '(:rays :spheres :overlaps)
                      collect (destructuring-bind (wall cpu bytes) (getf m key)
                                (list (round wall 1000) (round cpu 1000) bytes))))
        (finish-output stream))))
  (format stream "~&after the run: load ~A~%" (load-average)))
;; What a query costs:1 ends here

;; [[file:../physics.org::#LW3YHU][The page as HTML, and an index of the interface:2]]
(defun export-kinds (symbol)
  "What SYMBOL names in the image, as a list of words: macro, generic function, function, constant,
variable, condition, class, structure or type. #LW3YHU"
  (let ((class (find-class symbol nil)))
    (remove nil
            (list (cond ((macro-function symbol) "macro")
                        ((and (fboundp symbol) (typep (fdefinition symbol) 'generic-function)) "generic function")
                        ((fboundp symbol) "function"))
                  (cond ((constantp symbol) "constant")
                        ((boundp symbol) "variable"))
                  (cond ((null class) (and (sb-ext:valid-type-specifier-p symbol) "type"))
                        ((subtypep class 'condition) "condition")
                        ((typep class 'structure-class) "structure")
                        (t "class"))))))

(defun export-docstring (symbol)
  "The first docstring SYMBOL has as a function, a variable, a type or a structure, or NIL. #LW3YHU"
  (or (and (fboundp symbol) (documentation symbol 'function))
      (and (boundp symbol) (documentation symbol 'variable))
      (documentation symbol 'type)
      (documentation symbol 'structure)))

(defun docstring-anchor (docstring)
  "The anchor DOCSTRING ends with (the six characters after its last #), or NIL. #LW3YHU"
  (let* ((text (string-right-trim '(#\Space #\Newline) (or docstring "")))
         (at (position #\# text :from-end t)))
    (and at (= (- (length text) at) 7) (subseq text (1+ at)))))

(defun docstring-summary (docstring)
  "The first sentence of DOCSTRING, its lines joined, without the anchor at its end. #LW3YHU"
  (let* ((text (substitute #\Space #\Newline (string-trim '(#\Space #\Newline) docstring)))
         (anchor (docstring-anchor text))
         (text (if anchor (string-right-trim " " (subseq text 0 (- (length text) 7))) text))
         (end (loop for i from 0 below (1- (length text))
                    when (and (char= (char text i) #\.) (char= (char text (1+ i)) #\Space)
                              ;; not the point of an abbreviation such as e.g. or a number
                              (> i 1) (char/= (char text (- i 2)) #\.) (alpha-char-p (char text (1- i)))
                              (upper-case-p (char text (min (+ i 2) (1- (length text))))))
                      return (1+ i))))
    (string-trim " " (if end (subseq text 0 end) text))))

(defun api-index ()
  "One entry for each symbol the package luv-physics exports, sorted by name: a plist of :symbol,
:kinds (export-kinds), :arguments (a lambda list, or NIL), :docstring, :summary and :anchor (the
section of its definition on the page, or the anchor its docstring ends with). #LW3YHU"
  (let ((entries '()))
    (do-external-symbols (symbol '#:luv-physics)
      (let ((docstring (export-docstring symbol)))
        (push (list :symbol symbol :kinds (export-kinds symbol)
                    :arguments (and (fboundp symbol) (list (sb-introspect:function-lambda-list symbol)))
                    :docstring docstring
                    :summary (and docstring (docstring-summary docstring))
                    :anchor (or (definition-anchor symbol) (docstring-anchor docstring)))
              entries)))
    (sort entries #'string< :key (lambda (entry) (symbol-name (getf entry :symbol))))))

(defun org-table-text (text)
  "TEXT made safe for a cell of an Org table: no bar, no newline, and no asterisk that Org could
read as bold (a special variable's name has two). #LW3YHU"
  (with-output-to-string (out)
    (loop for c across text
          do (case c (#\| (write-string "\\vert{}" out)) (#\* (write-string "\\ast{}" out))
                   (#\Newline (write-char #\Space out))
                   (t (write-char c out))))))

(defun write-api-index (pathname)
  "Write the index of the exported symbols (api-index) to PATHNAME as an Org table, each name a
link to its section. Return the number of entries. #LW3YHU"
  (let ((entries (api-index)))
    (with-open-file (out pathname :direction :output :if-exists :supersede :external-format :utf-8)
      (format out "#+caption: the ~D symbols of the package luv-physics, from the loaded image~%" (length entries))
      (format out "| name | kind | arguments | what it is |~%|-~%")
      (dolist (entry entries)
        (format out "| [[#~A][=~(~A~)=]] | ~{~A~^, ~} | ~A | ~A |~%"
                (getf entry :anchor) (symbol-name (getf entry :symbol))
                (getf entry :kinds)
                (let ((arguments (getf entry :arguments)))
                  (if arguments
                      (format nil "~~~A~~"
                              (org-table-text (let ((*package* (find-package '#:luv-physics))
                                                    (*print-pretty* nil))
                                                (if (first arguments) (format nil "~(~S~)" (first arguments)) "()"))))
                      ""))
                (org-table-text (or (getf entry :summary) "")))))
    (length entries)))
;; The page as HTML, and an index of the interface:2 ends here

;; [[file:../physics.org::#O07FDP][Closing the files:1]]
(register-tangled-file #.(let ((here (or *compile-file-truename* *load-truename*)))
                           (and here (merge-pathnames "physics.lisp" here))))
(register-tangled-file #.(let ((here (or *compile-file-truename* *load-truename*)))
                           (and here (merge-pathnames "physics-simd.lisp" here))))
(register-tangled-file #.(or *compile-file-truename* *load-truename*))
;; Closing the files:1 ends here
