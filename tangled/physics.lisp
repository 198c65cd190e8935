;;;; tangled/physics.lisp -- GENERATED from physics.org by 'make tangle'. Do not edit.

;; [[file:../physics.org::#NEZQ3X][The package:1]]
(defpackage #:luv-physics
  (:use #:cl)
  (:nicknames #:physics)
  (:documentation "Rigid spheres in a block world, written as the literate page physics.org. #NEZQ3X")
  (:export
   ;; The image knows its anchors (#BSOZ3U)
   #:anchor-definitions
   #:definition-anchor
   ;; Which wide instructions this machine offers (#JKM0PY)
   #:available-kernel-families))

(in-package #:luv-physics)
;; The package:1 ends here

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
           (records
             (loop for scanned in (scan-tangled-text text)
                   collect (destructuring-bind (&key name kind anchor line source-line docstring)
                               scanned
                             (let* ((section (and anchor (gethash anchor sections)))
                                    (org-line
                                      (and section
                                           (or (page-line page-lines section source-line
                                                          (gethash anchor cursors (car section)))
                                               (page-line page-lines section source-line)))))
                               (when org-line
                                 (setf (gethash anchor cursors) (1+ org-line)))
                               (list :name name :kind kind :anchor anchor :file file
                                     :line line :org-line org-line :docstring docstring))))))
      (setf *definitions* (append (remove file *definitions*
                                          :key (lambda (record) (getf record :file))
                                          :test #'equal)
                                  records)
            *registered-files* (append (remove source *registered-files* :test #'equal)
                                       (list source))
            *page-pathname* (or page *page-pathname*))
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

;; [[file:../physics.org::#O07FDP][Closing the files:1]]
(register-tangled-file #.(or *compile-file-truename* *load-truename*))
;; Closing the files:1 ends here
